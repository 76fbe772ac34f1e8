r"""Bidirectional rendering: light tracing shares the paths the path tracer finds only by chance.

The paths it is for
-------------------
A path x0 (the eye), x1, ..., xk (on the light) of k segments belongs to the
class C when its first vertex x1 is diffuse and its last scattering vertex
x_{k-1} is a mirror. Going back from the light, the mirror chain then ends at a
diffuse vertex, so C is the set of paths ``eye D ... D S+ L``: the caustics the
mirror throws on the room (the ceiling lit by the light's image in the
sphere). Next-event estimation cannot sample them (the mirror is in the way);
the path tracer counts them only when a cosine-distributed bounce happens to
reflect off the mirror into the light, which is where its fireflies come from.

The partition
-------------
Both the path tracer and a light tracer can sample every class C path, once
each: the path tracer by its camera ray and cosine bounces up to the mirror,
the light tracer by a subpath from the light joined to the eye at x1. Each
counts a path with a weight, and the weights of a path add up to one, so the
sum is unbiased (multiple importance sampling). Paths outside C stay with
the path tracer as before.

``weights='binary'`` gives class C to the light tracer alone (the path
tracer's ``mirror_caustics='skip'``). ``weights='balance'`` (the default)
uses Veach's balance heuristic with n camera samples per pixel and N light
subpaths: the light tracer's weight is q / (1 + q), the path tracer's
1 / (1 + q), with q = N p_L / (n p_E), where p_L and p_E are the light and
the path tracer's densities of the path in the area measure of its vertices. Every diffuse vertex between x1
and the mirror chain is sampled by a cosine bounce in both (in opposite
directions: both give the factor G / pi), and the mirror chain's Jacobians
cancel because reflection conserves etendue (cos dA dw is the same at both
ends of a specular chain), so the ratio reduces to the ends of the path:

    q = (N / n) pi p_A(y0) p_w(w0) / (p_cam(x1) cos(theta_0)),    p_cam(x1) = W(w) cos(theta_x1) / d^2,

with p_A and p_w the light tracer's densities of its first point and
direction, theta_0 the angle of w0 to the light's normal, and p_cam the
density of x1 for one camera sample of its pixel. The path tracer evaluates
it where it hits the light (:meth:`CausticDensities.path_weight`), the light
tracer where it splats. N / n is a nominal constant (light_paths W H): the
weights add up to one whatever it is. Near the eye, where a pixel's patch is
small and the light tracer rarely hits it, the path tracer takes over.

The light tracer
----------------
A light subpath starts at y0, uniform on the light (density 1/A), along a
direction uniform in the cone of a mirror sphere seen from y0 (half-angle
theta_s, sin theta_s = r / |c - y0|, density 1 / (2 pi (1 - cos theta_s)); one
sphere chosen uniformly among several, the density their mixture): the first
vertex of a class C path from the light is a mirror, and every direction that
meets the sphere lies in its cone. Scenes with a mirror that is not a sphere
draw the cosine direction about the light's normal (density cos / pi) instead.
The subpath's weight starts at

    Le cos(theta_0) / (p_A(y0) p_w(w0)),

is multiplied by R at a mirror and by the albedo at a cosine-sampled diffuse
bounce (the path tracer's :meth:`mcrt.estimator.PathEstimator.scatter`), and
runs the path tracer's unbiased roulette. At each diffuse vertex y_j that
follows one or more mirror vertices, the subpath is joined to the eye (a path
of j + 1 segments, counted where j + 1 <= max_depth, the path tracer's
rule), if the vertex is lit on the side facing the eye and nothing (the
light's rectangle included) lies between them, into the pixel p that the
direction from the eye crosses:

    c_p = beta_j f(y_j) cos(theta_y) / d^2 W(w),    W(w) = 1 / (A_pix cos^3(theta)),

with f = albedo / pi, d the distance to the eye, theta the angle between the
direction and the camera's axis, and A_pix = (2 t_x / W)(2 t_y / H) the
pixel's area on the image plane at distance 1 (t_x = tan(fov_x / 2)). W is
the pixel's importance in solid angle: the path tracer draws its ray through a
uniform point of the pixel's square on that plane, whose density in solid
angle is 1 / (A_pix cos^3 theta) (dA = dw / cos^3 theta); in area measure,
with the camera's cosine in the geometry term, it is the familiar
1 / (A_pix cos^4 theta). With N light subpaths per pass, the pass estimates
pixel p by sum c_p / N (each c_p times its balance weight).

Determinism and variance
------------------------
Splats land on any pixel in any order; they are added as 64-bit fixed-point
integers (2^-SPLAT_BITS, far below any noise), so the sum does not depend on
which thread adds first and a seed gives the same image bit for bit.

The path tracer's image has its per-sample variance, as plain mcrt's. The
splats are no per-pixel samples (a light subpath adds to any pixels), so the
light tracer's variance is that of batch means: its N subpaths run in P
equal passes (:func:`batch_count`), pass k gives one estimate X_k of every pixel, and

    mean = (1/P) sum_k X_k,    Var(mean) = s_X^2 / P,    s_X^2 = sum_k (X_k - mean)^2 / (P - 1),

with P - 1 degrees of freedom per pixel, which the project's tile tests pool
over a tile's pixels. The two estimates are independent (their own random
streams), so the variance of their sum is the sum of their variances; the
result reports it times spp, so that variance / spp is Var(mean) as for
every renderer.
"""

from __future__ import annotations

import math

import drjit as dr
import numpy as np

from mcrt.bsdf import lambertian_f
from mcrt.camera import Pinhole
from mcrt.estimator import PathEstimator
from mcrt.film import Progress, RenderResult, run_passes
from mcrt.host import McrtHost
from mcrt.light import RectangleLight
from mcrt.minmax import fmax, fmin, sqrt0
from mcrt.mutants import check_mutants
from mcrt.options import Caustics, trick_options
from mcrt.rng import WeylRng
from mcrt.samplers import PixelSampler
from mcrt.sampling import coordinate_frame, cosine_about_normal, to_world
from mcrt.scene import Mirror, RenderSettings, Scene, Sphere
from mcrt.tracer import Tracer, backend_module, stream_keys

#: Passes (batches) of the light tracer, at most and at least: its variance's degrees of freedom + 1.
BATCHES, MIN_BATCHES = 32, 8
#: Light subpaths a batch has at least where the total allows: smaller launches leave cores idle.
BATCH_PATHS = 1 << 16
#: Fixed-point splats: a contribution is rounded to a multiple of 2^-SPLAT_BITS.
SPLAT_BITS = 28
#: Light subpaths per camera sample of the path tracer, by default.
LIGHT_PATHS = 0.05
#: The light tracer's pass k keys its streams as pass _LIGHT_STREAMS + k (mcrt.tracer.stream_keys), never a camera pass's.
_LIGHT_STREAMS = 1 << 40


def pinhole_importance(cos_theta, pixel_area, *, cos_power: int = 3):
    """W = 1 / (A_pix cos^3 theta): a pixel's importance per unit solid angle at the eye.

    ``cos_power`` other than 3 is a wrong importance, kept as an argument
    for the tests that must see it fail.
    """
    return dr.rcp(pixel_area * cos_theta**cos_power)


def mirror_cones(scene: Scene):
    """(centre, radius) of the mirror spheres whose cones a light subpath's first direction samples; None: cosine directions.

    Cones need every mirror to be a sphere that the light lies outside of.
    """
    mirrors = [o for o in scene.objects if isinstance(o.material, Mirror)]
    if not mirrors or not all(isinstance(o, Sphere) for o in mirrors):
        return None
    light = scene.light
    lo = np.asarray(light.center, float) - np.array([light.size[0] / 2, light.size[1] / 2, 0.0])
    hi = np.asarray(light.center, float) + np.array([light.size[0] / 2, light.size[1] / 2, 0.0])
    for s in mirrors:
        nearest = np.clip(np.asarray(s.center, float), lo, hi)
        if np.linalg.norm(nearest - np.asarray(s.center, float)) <= s.radius * (1 + 1e-4):
            return None
    return [(tuple(float(x) for x in s.center), float(s.radius)) for s in mirrors]


class CausticDensities:
    """What both strategies know of a class C path's densities: the camera's and the light tracer's (module docstring).

    Built from the scene, the camera at its resolution (:class:`mcrt.camera.Pinhole`)
    and ``light_paths``, N / n of the balance heuristic (light subpaths per
    camera sample of a pixel; 0 for binary weights). The path tracer's
    estimator is given it (``caustic_pdfs``) to weigh its light hits; the
    light tracer draws its first directions from its cones and splats
    through its camera frame.
    """

    def __init__(self, scene: Scene, camera: Pinhole, m, *, light_paths: float = 0.0):
        self.m = m
        self.light = RectangleLight(scene.light, m)
        self.width, self.height = camera.width, camera.height
        self.eye, self.forward = camera.eye, camera.center
        tx, ty = math.hypot(*camera.half_right), math.hypot(*camera.half_up)
        self.right = tuple(x / tx for x in camera.half_right)
        self.up = tuple(x / ty for x in camera.half_up)
        self.tx, self.ty = tx, ty
        self.pixel_area = (2.0 * tx / self.width) * (2.0 * ty / self.height)
        self.cones = mirror_cones(scene)
        self.caustic_paths = light_paths

    def camera_density(self, d, hit):
        """Area density at the first vertex of one camera sample of its pixel: W cos(theta_x) / t^2 (d from the eye)."""
        cos_cam = dr.dot(self.m.Array3f(*self.forward), d)
        return pinhole_importance(cos_cam, self.pixel_area) * (-dr.dot(hit.n, d) * dr.rcp(dr.square(hit.t)))

    def light_ratio(self, y0, w0, cos0):
        """pi p_A(y0) p_w(w0) / cos(theta_0): the light side of the densities' ratio (p_w without the sampled sphere's index)."""
        light = self.light
        if self.cones is None:
            return light.pdf_area  # p_w = cos / pi
        pdf = self.m.Float(0.0)
        for axis, s2, cos_max in self.cone_frames(y0):
            pdf += dr.select(dr.dot(w0, axis) >= cos_max, 1.0 / (2.0 * math.pi * (s2 / (1.0 + cos_max))), 0.0)
        return pdf * (math.pi * light.pdf_area / len(self.cones)) / cos0

    def path_weight(self, hit, d, cam_density):
        """The path tracer's balance weight 1 / (1 + q) of a light hit along d that ends a path eye D ... D S+ L."""
        q = self.caustic_paths * self.light_ratio(hit.p, -d, hit.light_cos) * dr.rcp(cam_density)
        return dr.rcp(1.0 + q)

    def cone_frames(self, y0):
        """(axis, sin^2 theta_s, cos theta_s) of each mirror sphere's cone seen from y0."""
        m = self.m
        frames = []
        for c, r in self.cones:
            to_c = m.Array3f(*c) - y0
            inv = dr.rsqrt(dr.squared_norm(to_c))
            s2 = dr.square(r * inv)
            frames.append((to_c * inv, s2, sqrt0(1.0 - s2)))
        return frames


class LightTracer:
    """The light tracer of the module docstring, on the path tracer's host and estimator.

    ``host`` (:class:`mcrt.host.McrtHost`) and ``estimator`` are the path
    tracer's (its bounces and roulette); ``densities`` its camera frame, cones
    and balance weights. ``importance_cos_power`` is
    :func:`pinhole_importance`'s (3, the correct importance).
    """

    def __init__(self, host: McrtHost, estimator: PathEstimator, densities: CausticDensities, *,
                 importance_cos_power: int = 3):
        self.host, self.estimator, self.densities = host, estimator, densities
        self.m = densities.m
        self.max_depth = estimator.max_depth
        self.cos_power = importance_cos_power
        self.width, self.height = densities.width, densities.height
        self._frozen = dr.freeze(self._light_pass, limit=4, warn_after=64)

    # ------------------------------------------------------------------
    def pass_moments(self, seed: int, pass_index: int, paths: int):
        """[X, X^2] of one pass of ``paths`` light subpaths, X = sum of splats / paths: Float64, laid out (moment, pixel, channel).

        X is the pass's estimate of every pixel (one batch of the module
        docstring's batch means). The work is :meth:`_light_pass`, frozen:
        recorded once per ``paths`` and replayed, the seed's keys opaque.
        """
        k0, k1 = stream_keys(seed, _LIGHT_STREAMS + pass_index)
        return self._frozen(dr.opaque(self.m.UInt32, k0), dr.opaque(self.m.UInt32, k1), paths)

    def _light_pass(self, key0, key1, paths: int):
        m = self.m
        rng = WeylRng.seeded(m, paths, key0, key1)
        size = 3 * self.width * self.height
        acc = dr.zeros(m.Int64, size)
        o, d, power, ratio, valid = self.emit(rng)
        self.trace(o, d, power, ratio, rng, acc, valid)
        dr.eval(acc)
        idx = dr.arange(m.UInt32, 2 * size)
        x = m.Float64(dr.gather(m.Int64, acc, idx % size)) * (2.0**-SPLAT_BITS / paths)
        out = dr.select(idx < size, x, x * x)
        dr.eval(out)
        return out

    # ---- Light subpaths --------------------------------------------------
    def emit(self, rng):
        """(origin, direction, Le cos / (p_A p_w), light_ratio, cos > 0) of light subpaths.

        A point uniform on the light, a direction towards the mirrors (or the cosine direction).
        """
        m, light = self.m, self.host.light
        u1, u2 = rng.next_1d(), rng.next_1d()
        (cx, cy, cz), (hx, hy) = light.center, light.half
        y0 = m.Array3f(dr.fma(u1, 2.0 * hx, cx - hx), dr.fma(u2, 2.0 * hy, cy - hy), cz)  # RectangleLight.sample's point
        n = (0.0, 0.0, light.normal_z)
        if self.densities.cones is None:
            d = m.Array3f(*cosine_about_normal(rng.next_1d(), rng.next_1d(), (m.Float(n[0]), m.Float(n[1]), m.Float(n[2]))))
            pdf = fmax(d.z * light.normal_z, 0.0) / math.pi
        else:
            d, pdf = self._sample_cones(y0, rng)
        cos0 = d.z * light.normal_z
        valid = cos0 > 0  # the light emits on its normal's side only
        power = dr.select(valid, light.emitted() * (cos0 * light.area / pdf), 0.0)
        ratio = self.densities.light_ratio(y0, d, cos0) if self.densities.caustic_paths else None
        origin = self.host.offset_along(y0, m.Array3f(*n))
        return origin, d, power, ratio, valid

    def _sample_cones(self, y0, rng):
        """A direction uniform in the cone of one mirror sphere chosen uniformly, and the mixture's density."""
        m = self.m
        count = len(self.densities.cones)
        pick = m.UInt32(fmin(rng.next_1d() * count, count - 1)) if count > 1 else m.UInt32(0)
        frames = self.densities.cone_frames(y0)
        axis, s2, cos_max = frames[0]
        for k in range(1, count):
            axis = dr.select(pick == k, frames[k][0], axis)
            s2 = dr.select(pick == k, frames[k][1], s2)
            cos_max = dr.select(pick == k, frames[k][2], cos_max)
        one_minus = s2 / (1.0 + cos_max)  # 1 - cos theta_s without cancellation
        cos_t = 1.0 - rng.next_1d() * one_minus
        sin_t = sqrt0((1.0 - cos_t) * (1.0 + cos_t))
        sp, cp = dr.sincos(2.0 * math.pi * rng.next_1d())
        s, t = coordinate_frame(axis.x, axis.y, axis.z)
        d = m.Array3f(*to_world((sin_t * cp, sin_t * sp, cos_t), s, t, (axis.x, axis.y, axis.z)))
        pdf = m.Float(0.0)
        for k, (a, s2_k, cm) in enumerate(frames):
            inside = (pick == k) | (dr.dot(d, a) >= cm)  # the chosen cone holds d, whatever rounding says
            pdf += dr.select(inside, 1.0 / (2.0 * math.pi * (s2_k / (1.0 + cm))), 0.0)
        return d, pdf * (1.0 / count)

    @dr.syntax
    def trace(self, o, d, power, ratio, rng, acc, active):
        """Follow light subpaths from (o, d) with weight ``power``, splatting at diffuse vertices after a mirror."""
        host, estimator, max_depth = self.host, self.estimator, self.max_depth
        beta = host.Spectrum(1.0)  # product of the bounce weights since the light
        depth = host.UInt32(0)  # segments traced from the light
        mirrored = host.Bool(False)  # the subpath has met a mirror
        active = host.Bool(active)
        while dr.hint(active, label="mcrt_light_path"):
            hit = host.intersect(o, d, active)
            depth += 1
            diffuse = active & hit.reflects & ~hit.mirror
            # ---- Join to the eye: a path of depth + 1 segments.
            self.splat(acc, hit, power * beta, ratio, diffuse & mirrored & (depth + 1 <= max_depth))
            # ---- Continue: a class C path from the light begins with a mirror vertex.
            alive = active & hit.reflects & (depth + 1 < max_depth) & (mirrored | hit.mirror)
            d, weight, _ = estimator.scatter(d, hit, alive, rng.next_1d(), rng.next_1d(), rng)
            beta *= weight
            mirrored |= hit.mirror
            o = host.spawn_origin(hit)
            beta, alive = estimator.roulette(beta, depth, diffuse, alive, rng)
            active = alive

    def splat(self, acc, hit, value, ratio, active):
        """Add value f cos(theta_y) / d^2 W (times the balance weight q / (1 + q)) to the pixel that sees the hit."""
        m, host, cam = self.m, self.host, self.densities
        to_eye = m.Array3f(*cam.eye) - hit.p
        inv_d = dr.rsqrt(dr.squared_norm(to_eye))
        w = to_eye * inv_d
        cos_y = dr.dot(hit.n, w)
        cos_cam = -dr.dot(m.Array3f(*cam.forward), w)
        ok = active & (cos_y > 0) & (cos_cam > 0)
        # The film coordinates (s_x, s_y) of mcrt.camera.Pinhole.film, inverted.
        sx = -dr.dot(m.Array3f(*cam.right), w) / (cam.tx * cos_cam)
        sy = -dr.dot(m.Array3f(*cam.up), w) / (cam.ty * cos_cam)
        col = (sx + 1.0) * (0.5 * self.width)
        row = (1.0 - sy) * (0.5 * self.height)
        ok &= (col >= 0) & (col < self.width) & (row >= 0) & (row < self.height)
        # A closest hit rather than a shadow test: the light's rectangle blocks the eye too.
        origin = host.spawn_origin(hit)
        to_eye_o = m.Array3f(*cam.eye) - origin
        ok &= host.intersect(origin, w, ok).t > dr.norm(to_eye_o)
        f = lambertian_f(hit.color, inv_pi=self.estimator.opt.mutations.brdf_inv_pi)
        g = cos_y * dr.square(inv_d)
        c = value * f * (g * pinhole_importance(cos_cam, cam.pixel_area, cos_power=self.cos_power))
        if ratio is not None:  # the light tracer's balance weight, q / (1 + q)
            q = cam.caustic_paths * ratio * dr.rcp(pinhole_importance(cos_cam, cam.pixel_area) * g)
            c = c * (q * dr.rcp(1.0 + q))
        pixel = m.UInt32(fmin(row, self.height - 1)) * self.width + m.UInt32(fmin(col, self.width - 1))
        for k in range(3):
            fixed = m.Int64(dr.round(m.Float64(c[k]) * float(2**SPLAT_BITS)))
            dr.scatter_reduce(dr.ReduceOp.Add, acc, fixed, pixel * 3 + k, ok)


# ----------------------------------------------------------------------
PARTS = ("both", "path", "light", "caustics")
WEIGHTS = ("balance", "binary")

#: Path tracers with their caustic split, densities and light tracers, kept for reuse (their kernels are recorded once).
_KEPT: dict = {}
KEPT = 8


def _path_tracer(scene: Scene, s: RenderSettings, *, caustics: Caustics, backend: str, intersector: str, mis: bool | None,
                 precision_guard: bool, mutants: frozenset = frozenset(), tricks: tuple = (),
                 pixel_sampler: PixelSampler = PixelSampler()):
    """(Tracer, CausticDensities, light tracers by importance power) for a render of ``scene`` at ``s`` with ``caustics``."""
    key = (scene.content_hash(), scene.path, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth,
           backend, intersector, mis, precision_guard, mutants, tricks, pixel_sampler, caustics)
    entry = _KEPT.get(key)
    if entry is None:
        densities = CausticDensities(scene, Pinhole(scene.camera(s.camera), s.width, s.height), backend_module(backend),
                                     light_paths=caustics.caustic_light_paths)
        tracer = Tracer(scene, s.camera, s.width, s.height, s.max_depth, s.light_samples, s.rr_depth, backend, intersector,
                        mutants, precision_guard, mis, tricks, pixel_sampler, caustics=caustics,
                        caustic_pdfs=densities if caustics.caustic_light_paths else None)
        if len(_KEPT) >= KEPT:
            _KEPT.pop(next(iter(_KEPT)))
        entry = _KEPT[key] = (tracer, densities, {})
    return entry


def _light_tracer(entry, cos_power: int) -> LightTracer:
    """The light tracer of a kept path tracer (on its host and estimator), kept with it: its pass is recorded once."""
    tracer, densities, light_tracers = entry
    if cos_power not in light_tracers:
        light_tracers[cos_power] = LightTracer(tracer.estimator.host, tracer.estimator, densities,
                                               importance_cos_power=cos_power)
    return light_tracers[cos_power]


def render_caustic_split(scene: Scene, settings: RenderSettings, *, mirror_caustics: str, backend: str = "llvm",
                         progress: bool = True, spp_per_pass: int | None = None, mutants=(), intersector: str = "convex",
                         mis: bool | None = None, precision_guard: bool = True, pixel_sampler: str = "independent",
                         replicates: int | None = None, **tricks) -> RenderResult:
    """The path tracer alone with ``mirror_caustics`` 'skip' or 'only' (:class:`mcrt.options.Caustics`): renderer ``mcrt``'s option.

    'only' renders the paths eye D ... D S+ L alone, to check the light
    tracer against; 'skip' everything else. ``pixel_sampler`` and
    ``replicates`` as in :func:`mcrt.tracer.render_tracer`.
    """
    if mirror_caustics not in ("skip", "only"):
        raise ValueError(f"mirror_caustics must be 'skip' or 'only' without a light tracer, got {mirror_caustics!r}")
    s = settings
    tracer = _path_tracer(scene, s, caustics=Caustics(mirror_caustics), backend=backend, intersector=intersector, mis=mis,
                          precision_guard=precision_guard, mutants=check_mutants(mutants), tricks=trick_options(tricks),
                          pixel_sampler=PixelSampler.of(pixel_sampler, replicates))[0]
    return tracer.render(seed=s.seed, spp=s.spp, progress=progress, spp_per_pass=spp_per_pass)


def batch_count(paths: int) -> int:
    """Batches of ``paths`` light subpaths: BATCH_PATHS each, MIN_BATCHES to BATCHES of them."""
    return min(BATCHES, max(MIN_BATCHES, paths // BATCH_PATHS))


def light_batches(light: LightTracer, *, seed: int, paths: int, progress: bool = True):
    """The light tracer's image from about ``paths`` light subpaths: (PassTotals, paths traced, batches).

    :func:`batch_count` equal passes; each pass k gives one estimate X_k of
    every pixel, the totals' mean is their mean and their variance the
    variance of one X_k.
    """
    batches = batch_count(paths)
    per_batch = max(1, -(-paths // batches))
    totals = run_passes(lambda k, _: light.pass_moments(seed, k, per_batch), width=light.width, height=light.height, spp=batches, spp_per_pass=1,
                        progress=Progress(batches, label="mcrt light tracing", unit="batches", enabled=progress))
    return totals, per_batch * batches, batches


#: light_paths 'auto': the pilot renders 1 / PILOT_SHARE of the samples (at least 16 per pixel), from other streams.
PILOT_SHARE = 16
PILOT_SEED = 0x51A7E
#: The budgets 'auto' chooses among: powers of two times LIGHT_PATHS (a few path kernels, compiled once each).
AUTO_LIGHT_PATHS = tuple(LIGHT_PATHS * 2.0**k for k in range(-3, 5))


def choose_light_paths(scene: Scene, settings: RenderSettings, *, pixel_sampler: str = "independent",
                       replicates: int | None = None, **common) -> tuple[float, dict]:
    r"""The light-path budget by the caustic paths' share of the variance, from a pilot render: (budget, pilot facts).

    With a light subpaths per camera sample, the render's relMSE-weighted
    variance and its time per camera sample are about

    .. math::  V(\lambda) = \frac{a + b / \lambda}{n}, \qquad T(\lambda) = n (t_p + \lambda t_l),

    a the path tracer's variance per camera sample (everything but the light
    tracer's share), b the light tracer's at one subpath per camera sample,
    t_p and t_l the times of one camera sample and one light subpath. Their
    product, the inverse efficiency, is least at
    :math:`\lambda^* = \sqrt{b\, t_p / (a\, t_l)}`: the more of the
    variance the caustic class holds, the more light subpaths pay. The pilot
    (both parts at LIGHT_PATHS, 1 / PILOT_SHARE of the samples, seeds apart
    from the render's) measures a, b, t_p and t_l; the budget is the entry
    of AUTO_LIGHT_PATHS nearest lambda* on a log scale. The pilot's samples
    are not reused: the render stays unbiased whatever it chooses.
    """
    from dataclasses import replace

    from mcrt import metrics as M

    reps = PixelSampler.of(pixel_sampler, replicates).replicates
    n = max(16, settings.spp // PILOT_SHARE)
    n = -(-n // reps) * reps
    pilot = replace(settings, spp=n, seed=settings.seed ^ PILOT_SEED)
    kw = dict(common, progress=False, light_paths=LIGHT_PATHS, pixel_sampler=pixel_sampler, replicates=replicates)
    path = render_bidirectional(scene, pilot, part="path", **kw)
    light = render_bidirectional(scene, pilot, part="light", **kw)
    w = 1.0 / (np.square(path.mean.astype(np.float64) + light.mean) + M.RELMSE_EPS)
    a = float((w * path.variance).mean())  # per camera sample
    b = float((w * light.variance).mean()) * LIGHT_PATHS  # light.variance / n is its Var(mean) at LIGHT_PATHS
    seconds = [r.wall_time - (r.compile_time or 0.0) for r in (path, light)]
    t_p, t_l = seconds[0] / n, seconds[1] / (n * LIGHT_PATHS)
    best = math.sqrt(b * t_p / (a * t_l)) if a > 0 and b > 0 and t_l > 0 else LIGHT_PATHS
    chosen = min(AUTO_LIGHT_PATHS, key=lambda x: abs(math.log(x / best)))
    return chosen, {"a": a, "b": b, "t_p": t_p, "t_l": t_l, "optimum": best, "seconds": sum(seconds), "spp": n}


def render_bidirectional(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                         spp_per_pass: int | None = None, mutants=(), intersector: str = "convex",
                         mis: bool | None = None, precision_guard: bool = True, mirror_caustics: str = "all",
                         light_paths: float | str = LIGHT_PATHS, weights: str = "balance", part: str = "both",
                         importance_cos_power: int = 3, pixel_sampler: str = "independent",
                         replicates: int | None = None, **tricks) -> RenderResult:
    """Render ``scene`` with the path tracer and, for the paths eye D ... D S+ L (class C), light tracing.

    Renderer ``mcrt`` with ``bidirectional=True`` (:func:`mcrt.render.render`)
    calls it with that renderer's options; it refuses ``mutants`` and
    ``mirror_caustics`` (it sets those itself). The path tracer renders
    ``settings`` as plain mcrt does (``spp_per_pass`` and ``tricks``,
    :data:`mcrt.options.TRICK_OPTIONS`, are its),
    the light tracer ``light_paths`` subpaths per camera sample (light_paths
    spp W H in all). ``weights`` 'balance' shares class C between them by
    the balance heuristic, 'binary' leaves it to the light tracer alone
    (module docstring). The two are independent, so the variance of the sum
    is the sum of the path tracer's per-sample variance over spp and the
    light tracer's variance of batch means over its passes; the result
    reports it as spp times that.

    ``part`` renders a share, for checks: 'path' the path tracer's, 'light'
    the light tracer's, 'caustics' both strategies' shares of class C alone
    (to compare with plain mcrt's ``mirror_caustics='only'``);
    ``importance_cos_power`` as in :func:`pinhole_importance`.
    ``pixel_sampler`` and ``replicates`` are the path tracer's
    (:mod:`mcrt.samplers`); with replicates the result's variance has
    min(R, light batches) - 1 degrees of freedom, and says so.
    ``light_paths='auto'`` chooses the budget from a pilot render
    (:func:`choose_light_paths`), whose time the result's wall time includes.
    """
    if mutants or mirror_caustics != "all":
        raise ValueError("bidirectional rendering takes no mutants and no mirror_caustics (it sets them itself)")
    tricks = trick_options(tricks)
    if part not in PARTS:
        raise ValueError(f"part must be one of {', '.join(PARTS)}, got {part!r}")
    if weights not in WEIGHTS:
        raise ValueError(f"weights must be one of {', '.join(WEIGHTS)}, got {weights!r}")
    pilot = None
    if light_paths == "auto":
        light_paths, pilot = choose_light_paths(scene, settings, pixel_sampler=pixel_sampler, replicates=replicates,
                                                backend=backend, intersector=intersector, mis=mis,
                                                precision_guard=precision_guard, weights=weights, **dict(tricks))
    if isinstance(light_paths, str) or light_paths <= 0:
        raise ValueError(f"light_paths must be > 0 or 'auto', got {light_paths!r}")
    s = settings
    sampler = PixelSampler.of(pixel_sampler, replicates)
    # N / n of the balance heuristic: light subpaths per camera sample of a pixel (nominal; any constant is unbiased).
    ratio = light_paths * s.width * s.height if weights == "balance" else 0.0
    caustics = "only" if part == "caustics" else ("mis" if ratio else "skip")
    entry = _path_tracer(scene, s, caustics=Caustics(caustics, ratio), backend=backend, intersector=intersector, mis=mis,
                         precision_guard=precision_guard, tricks=tricks, pixel_sampler=sampler)
    tracer = entry[0]
    shape = (s.height, s.width, 3)
    mean, var_of_mean = np.zeros(shape, np.float64), np.zeros(shape, np.float64)
    wall = compile_time = 0.0
    extra = {}
    if part == "path" or part == "both" or (part == "caustics" and ratio):  # binary: the light tracer's class alone
        pt = tracer.render(seed=s.seed, spp=s.spp, progress=progress, spp_per_pass=spp_per_pass)
        mean += pt.mean
        var_of_mean += pt.variance.astype(np.float64) / pt.spp
        wall, compile_time, extra = pt.wall_time, pt.compile_time or 0.0, dict(pt.extra)
    if part != "path":
        light = _light_tracer(entry, importance_cos_power)
        totals, paths, batches = light_batches(light, seed=s.seed, paths=round(light_paths * s.spp * s.width * s.height),
                                               progress=progress)
        mean += totals.mean
        var_of_mean += totals.variance.astype(np.float64) / batches
        wall, compile_time = wall + totals.wall_time, compile_time + totals.compile_time
        extra.update(mis=str(tracer.options.settings.mis).lower(), light_paths=str(paths), light_batches=str(batches))
        if pilot is not None:
            wall += pilot["seconds"]
            extra["light_paths_pilot"] = ",".join(f"{k}={v:.4g}" for k, v in pilot.items())
        if not sampler.default:  # the fewer independent estimates of the two bound the sum's degrees of freedom
            extra["variance_method"] = f"replicates:{min(sampler.replicates, batches)}"
    return RenderResult(
        mean=mean.astype(np.float32),
        variance=(var_of_mean * s.spp).astype(np.float32),
        spp=s.spp,
        seed=s.seed,
        max_depth=s.max_depth,
        renderer="mcrt",
        scene_hash=scene.content_hash(),
        camera=s.camera,
        wall_time=wall,
        compile_time=compile_time,
        extra={**extra, "bidirectional": part, "weights": weights,
               "variance": "path samples + light batch means", "drjit_version": dr.__version__},
    )
