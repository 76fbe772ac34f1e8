r"""mcrt's path estimator, written once against a small interface of the scene it runs in.

For a camera ray the estimator returns an unbiased sample of the pixel's
radiance, the measurement of

    L(x, wo) = Le(x, wo) + int_H f(x, wi, wo) L(x', -wi) cos(theta_i) dwi

truncated to paths of at most ``max_depth`` segments (Mitsuba's convention:
1 sees emitters only, 2 adds direct light, -1 is unbounded). At a Lambertian
vertex x the integral is split into

- direct light, from K points y_k sampled on the light with area density
  p_A (next-event estimation), each tested for visibility V by a shadow ray:

      L_direct = (1/K) sum_k f Le V cos(theta_x) cos(theta_y) / (|x - y_k|^2 p_A(y_k));

- indirect light, along one cosine-weighted direction (pdf cos/pi), whose
  weight f cos / pdf is the albedo; light that this ray finds is not counted
  (the direct term has it), except by multiple importance sampling.

A mirror reflects with weight equal to its reflectance; emission seen from
the eye or after a mirror is counted, because no light sample could have
found it. Emission of surfaces that next-event estimation does not sample is
counted at every hit. Russian roulette from ``rr_depth`` on keeps a path
with probability q = min(max(throughput), 0.95) and divides the throughput by q.

Where a lit surface nearly touches the light, area sampling alone has
unbounded variance (the 1/d^2); there (``mis``) light samples and the cosine
direction are combined by the balance heuristic, in solid angle.
Sampling the light uniformly in the solid angle Omega it subtends instead
(``light_sampling='solid_angle'``, a spherical rectangle) has the area
density p_A = cos(theta_y) / (d^2 Omega), so the sample's weight
Le V cos(theta_x) Omega is bounded without MIS. Without light sampling
(``light_sampling='none'``) the direct term is left out and emission is
counted wherever a ray meets it, with weight 1: the same mean, far more
noise (a student's tracer without next-event estimation).

The host
--------
:class:`PathEstimator` never asks which scene it runs in: it asks a
:class:`Host` (a typing.Protocol, below) for closest hits, light samples,
occlusion and spawned rays; solid-angle light sampling is an optional
capability (:class:`SolidAngleLightHost`).

Its inputs are explicit: the host, :class:`mcrt.options.EstimatorOptions`
(render settings, catalogued mutations, tricks, the caustic split), and, for
balance weights against a light tracer, that tracer's densities
(``caustic_pdfs``, :mod:`mcrt.bidir`). Every bug of the catalogue
(:mod:`mcrt.mutants`) is a value of a typed field of
:class:`mcrt.options.Mutations` whose default is the correct physics.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import drjit as dr

from mcrt.bsdf import lambertian_f, lambertian_weight, mistaken_bounce, mistaken_mirror, reflect, sample_lambertian
from mcrt.light import solid_angle_pdf
from mcrt.minmax import fmin
from mcrt.options import EstimatorOptions
from mcrt.sampling import balance_heuristic, cosine_hemisphere_pdf

#: Shadow rays stop this fraction short of the light point, so that they never hit the light itself.
SHADOW_TMAX_SCALE = 1.0 - 2.0**-12


@dataclass
class Hit:
    """What the estimator needs of a ray's closest hit (every field an array over lanes).

    ``n`` is the unit geometric normal on the side the ray arrived from;
    ``reflects`` whether the surface scatters light (false for the light's
    black surface and for rays that hit nothing); ``color`` the albedo of a
    Lambertian surface or the reflectance of a mirror; ``light`` whether the
    hit lies on a light that :meth:`Host.sample_light` samples, with
    ``light_cos`` the cosine between -d and its emitting-side normal and
    ``light_radiance`` the radiance of its emitting side; ``emission`` the
    radiance towards the ray of surfaces no light sample reaches (None
    where the scene has none); ``valid`` whether the ray hit anything.
    """

    t: object
    p: object
    n: object
    reflects: object
    mirror: object
    color: object
    light: object
    light_cos: object
    light_radiance: object
    emission: object = None
    valid: object = True
    extra: object = None  # what the host keeps for its own later calls (Mitsuba's SurfaceInteraction)


class Host(Protocol):
    """What :class:`PathEstimator` asks of the scene it runs in (required of every host).

    :class:`mcrt.host.McrtHost` implements it on mcrt's own geometry (a
    kernel specialised to the scene: nothing is traced that the scene lacks)
    and :class:`mcrt.plugins.host.MitsubaHost` on a Mitsuba scene, so the
    standalone tracer and the Mitsuba plugin run this estimator by
    construction.
    """

    # The array types of the host's backend.
    Float: type
    UInt32: type
    Bool: type
    Vector3f: type
    Spectrum: type
    # What the scene holds (Python bools: code for what a scene lacks is not traced).
    has_diffuse: bool
    has_mirror: bool
    has_unsampled_emission: bool  # surfaces that emit where no light sample reaches (counted at every hit)
    rays_escape: bool  # rays can leave the scene (false for the closed room)

    def intersect(self, o, d, active=True) -> Hit:
        """The closest hit of rays (o, d), d of unit length."""

    def sample_light(self, x, u1, u2, active=True):
        """A point on a light seen from x (:class:`mcrt.light.LightSample`: radiance and area density)."""

    def light_pdf_area(self, hit: Hit, active=True):
        """The area density with which :meth:`sample_light` would have chosen a hit light point (for MIS)."""

    def occluded(self, o, d, tmax, active=True):
        """Whether anything but the light blocks o + t d, 0 < t < tmax (None: the whole ray; a closed scene blocks it)."""

    def spawn_origin(self, hit: Hit):
        """The origin of rays leaving a hit, offset against self-intersection on the side the ray arrived from."""


@runtime_checkable
class SolidAngleLightHost(Host, Protocol):
    """An optional capability: light points uniform in the solid angle the light subtends (``light_sampling='solid_angle'``)."""

    def sample_light_solid_angle(self, x, u1, u2, active=True):
        """A point on the light uniform in its solid angle seen from x (pdf_area cos_y / (d^2 Omega))."""


def _max_component(v):
    """The largest component; for three by two compares (dr.max also orders NaNs and signed zeros, at a cost)."""
    if dr.size_v(v) != 3:
        return dr.max(v)
    a = dr.select(v.x > v.y, v.x, v.y)
    return dr.select(a > v.z, a, v.z)


class PathEstimator:
    """The path loop of the module docstring on one host.

    ``caustic_pdfs``: with balance weights for the paths eye D ... D S+ L
    (``options.caustics.caustic_light_paths`` > 0), the densities that both
    the path tracer and the light tracer evaluate
    (:class:`mcrt.bidir.CausticDensities`).
    """

    def __init__(self, host: Host, options: EstimatorOptions, *, caustic_pdfs=None):
        self.host, self.opt = host, options
        self.max_depth = options.depth_limit
        if options.tricks.light_sampling == "solid_angle" and not isinstance(host, SolidAngleLightHost):
            raise ValueError(f"{type(host).__name__} has no solid-angle light sampling (mcrt's own host has)")
        if options.caustics.caustic_light_paths > 0 and caustic_pdfs is None:
            raise ValueError("mirror_caustics 'mis' needs the light tracer's densities (caustic_pdfs, mcrt.bidir)")
        self.caustic_pdfs = caustic_pdfs
        # Whether light found by a diffuse bounce counts: only then does a
        # path whose last vertex is diffuse need its final segment traced.
        self.sample_light = options.tricks.light_sampling != "none"
        self.diffuse_sees_emission = (options.settings.mis or host.has_unsampled_emission or not self.sample_light
                                      or options.mutations.count_emission == "always")

    # ------------------------------------------------------------------
    @dr.syntax
    def path_sums(self, o, d, sampler, active=True, new_path=None):
        """Sums of x and x^2 over the radiance samples x traced in turn by each lane.

        The first path starts along the rays (o, d). Without ``new_path`` a
        lane traces that one path. With it, ``new_path(ended, sampler)``,
        given the lanes whose path ended (or that have none in flight),
        returns (restart, o, d): the lanes that start another path (it may
        reseed their random streams) and the camera rays of every lane; a
        restarted lane follows its new ray in the same loop iteration (path
        regeneration), so a packet runs until its lanes' total work is done
        instead of until its longest path ends. Returns (sum x, sum x^2,
        hit), ``hit`` whether the first ray hit anything.
        """
        # Plain Python values only: dr.syntax treats the locals the loop reads as loop state.
        host = self.host
        spawn_offset, brdf_inv_pi = self.opt.mutations.spawn_offset, self.opt.mutations.brdf_inv_pi
        mis = self.opt.settings.mis
        caustics = self.opt.caustics.mirror_caustics
        clamp = self.opt.tricks.sample_clamp  # None, or each finished path's radiance clamped to it per channel

        # ---- Loop state.
        L = host.Spectrum(0.0)  # radiance of the current path gathered so far
        beta = host.Spectrum(1.0)  # path throughput: product of f cos / pdf so far
        depth = host.UInt32(0)  # segments of the current path traced so far
        specular = host.Bool(True)  # the last vertex was the eye or a mirror: count emission
        pdf_bsdf = host.Float(0.0)  # solid-angle pdf of the last cosine direction (for MIS)
        sum_x = host.Spectrum(0.0)  # the lane's finished samples: sum of x
        sum_x2 = host.Spectrum(0.0)  # and of x^2
        hit_first = host.Bool(False)  # the first ray hit something
        eye_diffuse = host.Bool(False)  # the current path's first vertex is diffuse (mirror_caustics)
        cam_density = host.Float(0.0)  # area density of the first vertex per camera sample (mirror_caustics 'mis')
        balance = self.opt.caustics.caustic_light_paths > 0
        active = host.Bool(active) & (self.max_depth > 0)  # the lane has a path in flight

        while dr.hint(active, label="mcrt_path"):
            hit = host.intersect(o, d, active)
            depth += 1
            if host.rays_escape:
                hit_first |= hit.valid & (depth == 1)

            # ---- Emission.
            if caustics != "all":
                eye_diffuse = dr.select(depth == 1, hit.reflects & ~hit.mirror, eye_diffuse)
            if balance:
                cam_density = dr.select(depth == 1, self.caustic_pdfs.camera_density(d, hit), cam_density)
            # The balance weight of this hit where it ends a path eye D ... D S+ L.
            w_caustic = self.caustic_pdfs.path_weight(hit, d, cam_density) if balance else 1.0
            L = dr.fma(beta, self.emitted(hit, specular, pdf_bsdf, depth, active, eye_diffuse=eye_diffuse,
                                          caustic_weight=w_caustic), L)
            if hit.emission is not None and caustics != "only":
                L = dr.fma(beta, hit.emission, L)

            # ---- Stop where nothing reflects (the light) and at the depth limit.
            alive = hit.reflects & (depth < self.max_depth)
            origin = host.spawn_origin(hit) if spawn_offset else hit.p
            diffuse = alive & ~hit.mirror if host.has_mirror else alive
            if not self.diffuse_sees_emission:
                # The last segment after a diffuse vertex could only find emission,
                # which the light sample here has already counted: end the path.
                alive = alive & (hit.mirror | (depth + 1 < self.max_depth))

            # ---- Next-event estimation at diffuse vertices (depth + 1 <= max_depth holds here).
            if host.has_diffuse and caustics != "only" and self.sample_light:
                f = lambertian_f(hit.color, inv_pi=brdf_inv_pi)
                L = dr.fma(beta * f, self.direct_light(origin, hit.n, sampler, diffuse), L)

            # ---- Continue: cosine-weighted Lambertian direction or mirror reflection.
            u1, u2 = sampler.next_1d(), sampler.next_1d()
            d, weight, specular = self.scatter(d, hit, alive, u1, u2, sampler, depth)
            if mis:
                pdf_bsdf = cosine_hemisphere_pdf(dr.dot(hit.n, d))
            beta *= weight
            o = origin

            # ---- Russian roulette.
            beta, alive = self.roulette(beta, depth, diffuse, alive, sampler)

            # ---- A path that ended is added to the sums; its lane starts the next one.
            ended = ~alive
            x = L if clamp is None else dr.select(L > clamp, clamp, L)  # the finished sample, clamped where asked
            sum_x = dr.select(ended, sum_x + x, sum_x)
            sum_x2 = dr.select(ended, dr.fma(x, x, sum_x2), sum_x2)
            L = dr.select(ended, 0.0, L)
            if new_path is None:
                active = alive
            else:
                restart, o_new, d_new = new_path(ended, sampler)
                o = dr.select(restart, o_new, o)
                d = dr.select(restart, d_new, d)
                beta = dr.select(restart, 1.0, beta)
                depth = dr.select(restart, 0, depth)
                specular |= restart
                active = alive | restart
        return sum_x, sum_x2, hit_first

    # ------------------------------------------------------------------
    def emitted(self, hit, specular, pdf_bsdf, depth, active, eye_diffuse=False, caustic_weight=1.0):
        """Le towards the ray where it meets a light's emitting side, weighted against light sampling.

        Without MIS it counts only where no light sample could have found it
        (from the eye, after a mirror). With MIS a hit after a diffuse bounce
        counts too, with the balance weight of the cosine direction against
        K light samples, both densities in solid angle. ``mirror_caustics``
        drops (or keeps alone, or weighs by ``caustic_weight``) the hits
        after a mirror on paths whose first vertex was diffuse
        (``eye_diffuse``): the paths eye D ... D S+ L.
        """
        opt = self.opt
        cos_y = hit.light_cos if opt.mutations.light_one_sided else dr.abs(hit.light_cos)
        seen = hit.light & (cos_y > 0)
        weight = 1.0
        if opt.mutations.count_emission == "always" or not self.sample_light:
            counted = seen  # counted twice (a bug), or the only way the light is found (no light sampling)
        elif not opt.settings.mis:
            counted = seen & specular
        else:
            counted = seen
            p_light = solid_angle_pdf(self.host.light_pdf_area(hit, active), dr.square(hit.t), cos_y)
            weight = dr.select(specular, 1.0, balance_heuristic(1, pdf_bsdf, opt.settings.light_samples, p_light))
        if opt.settings.hide_emitters:
            counted = counted & (depth > 1)
        if opt.caustics.mirror_caustics != "all":
            caustic = specular & eye_diffuse  # after a mirror (specular at depth > 1: eye_diffuse is false at depth 1)
            if opt.caustics.mirror_caustics in ("skip", "only"):
                counted = counted & (caustic if opt.caustics.mirror_caustics == "only" else ~caustic)
            if opt.caustics.caustic_light_paths:
                weight = dr.select(caustic, caustic_weight, weight)
        return dr.select(counted, hit.light_radiance * weight, 0.0)

    def scatter(self, d, hit, alive, u1, u2, sampler, depth=None):
        """Next direction from (u1, u2), its weight f cos / pdf, and whether the bounce was specular (a mirror).

        With the trick ``bounce`` the Lambertian bounce is one of
        :func:`mcrt.bsdf.mistaken_bounce`'s on a camera path (``depth``, its
        segments so far, given), at every vertex or (``bounce_at`` 'first') at
        its first vertex only; with ``mirror``, the mirror's reflection one of
        :func:`mcrt.bsdf.mistaken_mirror`'s (``mirror_at`` likewise).
        """
        host, opt = self.host, self.opt
        d_next = sample_lambertian(host.Vector3f, hit.n, u1, u2, sampler, method=opt.mutations.lambertian_sampler)
        weight = lambertian_weight(hit.color, inv_pi=opt.mutations.brdf_inv_pi)
        if opt.tricks.bounce != "cosine" and depth is not None:
            d_bad, w_bad = mistaken_bounce(host.Vector3f, hit.n, u1, u2, weight, opt.tricks.bounce)
            at = (depth == 1) if opt.tricks.bounce_at == "first" else True
            d_next, weight = dr.select(at, d_bad, d_next), dr.select(at, w_bad, weight)
        if not host.has_mirror:
            return d_next, weight, host.Bool(False)
        mirror = alive & hit.mirror
        r = reflect(d, hit.n, sign=opt.mutations.mirror_sign)
        w_mirror = hit.color
        if opt.tricks.mirror != "reflect" and depth is not None:
            r_bad, k = mistaken_mirror(host.Vector3f, d, hit.n, hit.p, opt.tricks.mirror,
                                       normal_length=opt.tricks.mirror_normal_length)
            # A path that meets the mirror after its first hit ends there ('camera_only'); the others at the
            # first hit only, or at every hit.
            at = (depth > 1) if opt.tricks.mirror == "camera_only" else (
                (depth == 1) if opt.tricks.mirror_at == "first" else True)
            r, w_mirror = dr.select(at, r_bad, r), dr.select(at, w_mirror * k, w_mirror)
        return dr.select(mirror, r, d_next), dr.select(mirror, w_mirror, weight), mirror

    def roulette(self, beta, depth, diffuse, alive, sampler):
        """Russian roulette from depth ``roulette_start`` (default ``rr_depth``): survive with q, then beta /= q.

        Unbiased: E[beta'] = q (beta / q) = beta, with q = min(max beta, 0.95)
        from the throughput, or the fixed ``roulette_survival``. The 2023
        course's scheme (``roulette='course2023'``) instead absorbs a path at
        a diffuse vertex with probability 1 - q = 0.75 and multiplies a
        survivor by 0.8 (E[beta'] = 0.2 beta: biased), at every diffuse
        vertex unless ``roulette_start`` is given.
        """
        opt = self.opt
        if opt.mutations.roulette == "course2023":
            absorb = 0.75 if opt.tricks.roulette_survival is None else 1.0 - opt.tricks.roulette_survival
            survive = sampler.next_1d() >= absorb
            if opt.tricks.roulette_start is not None:
                diffuse = diffuse & (depth >= opt.tricks.roulette_start)
            return dr.select(diffuse, beta * 0.8, beta), alive & (~diffuse | survive)
        q = fmin(_max_component(beta), 0.95) if opt.tricks.roulette_survival is None else opt.tricks.roulette_survival
        roulette = alive & (depth >= (opt.settings.rr_depth if opt.tricks.roulette_start is None else opt.tricks.roulette_start))
        survive = sampler.next_1d() < q
        return dr.select(roulette, beta * dr.rcp(q), beta), alive & (~roulette | survive)

    # ------------------------------------------------------------------
    def direct_light(self, origin, n, sampler, active):
        """(1/K) sum_k Le V G / p_A over K light samples: the direct light over f. K = 1 traces no loop."""
        if self.opt.settings.light_samples == 1:
            return self.light_sample(origin, n, sampler, active)
        return self._light_sample_loop(origin, n, sampler, active) * (1.0 / self.opt.settings.light_samples)

    @dr.syntax
    def _light_sample_loop(self, origin, n, sampler, active):
        acc = self.host.Spectrum(0.0)  # sum of the light samples so far
        k = self.host.UInt32(0)  # light samples drawn
        while dr.hint(active & (k < self.opt.settings.light_samples), label="mcrt_light_samples"):
            acc += self.light_sample(origin, n, sampler, active)
            k += 1
        return acc

    def light_sample(self, origin, n, sampler, active):
        """One light sample seen from ``origin`` with unit normal ``n``: Le V G / p_A, G = cos_x cos_y / d^2.

        Its expectation over the light is the irradiance the light gives the
        point, E = int Le V cos_x cos_y / d^2 dA (with MIS, the light
        sampling's share of it).
        """
        host, opt = self.host, self.opt
        sample = host.sample_light if opt.tricks.light_sampling == "area" else host.sample_light_solid_angle
        ls = sample(origin, sampler.next_1d(), sampler.next_1d(), active)
        cos_x = dr.dot(n, ls.wi)
        cos_y = ls.cos_y if opt.mutations.light_one_sided else dr.abs(ls.cos_y)
        valid = active & (cos_x > 0) & (cos_y > 0)
        g = self.geometry_term(cos_x, cos_y, ls.inv_dist)
        tmax = ls.dist2 * ls.inv_dist * SHADOW_TMAX_SCALE if opt.mutations.shadow_bounded else None
        blocked = host.occluded(origin, ls.wi, tmax, valid)
        if opt.settings.mis:
            p_light = solid_angle_pdf(ls.pdf_area, ls.dist2, cos_y)
            g = g * balance_heuristic(opt.settings.light_samples, p_light, 1, cosine_hemisphere_pdf(cos_x))
        pdf = ls.pdf_area if opt.mutations.nee_pdf_area else 1.0
        return dr.select(valid & ~blocked, ls.radiance * (g / pdf), 0.0)

    def geometry_term(self, cos_x, cos_y, inv_dist):
        """G = cos_x cos_y / d^2, less the factors a catalogued bug leaves out."""
        opt = self.opt
        g = self.host.Float(1.0)
        if opt.mutations.nee_cos_surface:
            g = cos_x
        if opt.mutations.nee_cos_light:
            g = g * cos_y
        if opt.mutations.nee_inv_dist2:
            g = g * dr.square(inv_dist)
        return g
