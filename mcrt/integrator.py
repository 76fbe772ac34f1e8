"""The path-tracing estimator with next-event estimation to the area light.

For a camera ray the estimator returns an unbiased sample of the pixel's
radiance, the measurement of

    L(x, wo) = Le(x, wo) + int_H f(x, wi, wo) L(x', -wi) cos(theta_i) dwi

truncated to paths of at most ``max_depth`` segments (Mitsuba's convention:
1 sees emitters only, 2 adds direct light). At a Lambertian vertex the
integral is split into

- direct light, by sampling K points y_k uniformly on the light (pdf_area = 1/A):

      L_direct = (1/K) sum_k (albedo/pi) Le V(x, y_k) cos(theta_x) cos(theta_y) / |x - y_k|^2 * A

- indirect light, by one cosine-weighted direction (pdf = cos/pi), whose weight
  f cos / pdf is the albedo; emission found by that ray is not counted (the
  direct term already has it).

A mirror reflects along d - 2 (d.n) n with weight equal to its reflectance;
emission seen from the camera or after a mirror is counted, because no light
sample could have produced it. Russian roulette from ``rr_depth`` on keeps a
path with probability q = min(max(throughput), 0.95) and divides the
throughput by q, so the estimate stays unbiased.
"""

from __future__ import annotations

import math

import drjit as dr

from mcrt.geometry import KIND_LAMBERTIAN, KIND_MIRROR, SHADOW_TMAX_SCALE, Geometry
from mcrt.sampling import (
    INV_PI,
    coordinate_frame,
    cosine_about_normal,
    square_to_uniform_ball,
    square_to_uniform_hemisphere,
    to_world,
)

UNBOUNDED = 2**32 - 1


def needs_mis(scene) -> bool:
    """Whether a surface comes closer to the light than the light's larger side.

    Light sampling by area has a weight ~ 1/d^2 that is unbounded where a
    lit surface meets the light (a light touching a wall, a light just above
    the floor); there the estimator switches on MIS with cosine sampling,
    which bounds it. Faces behind the light (the ceiling above a light that
    faces down) receive none of its light and do not count.
    """
    import numpy as np

    light = scene.light
    corners = light.corners()
    reach = max(light.size)
    for plane in scene.room.planes():
        n, h = plane[:3], plane[3]
        if abs(n[2]) > 0.5 and n[2] * light.normal[2] < 0:  # outward normal against the light normal
            continue  # the face behind the light
        if np.min(h - corners @ n) < reach:
            return True
    return False


def _max3(v):
    """The largest of three components by compares (dr.max also orders NaNs and signed zeros, at a cost)."""
    a = dr.select(v.x > v.y, v.x, v.y)
    return dr.select(a > v.z, a, v.z)


class PathIntegrator:
    """Lambertian + mirror path tracer with K light samples per diffuse vertex.

    Only what the scene holds is traced into the kernel: no mirror code
    without a mirror, no light-sampling loop when K = 1, and multiple
    importance sampling (``mis``) only where the scene needs it: a light
    touching or nearly touching a surface, where area sampling alone has
    unbounded variance (see :func:`needs_mis`).
    """

    def __init__(self, geometry: Geometry, *, max_depth: int, light_samples: int = 1, rr_depth: int = 5, mutants=frozenset(),
                 mis: bool = False):
        self.geo = geometry
        self.mis = mis
        self.m = geometry.m
        self.mutants = frozenset(mutants)
        depth = max_depth if max_depth > 0 else UNBOUNDED
        if "depth_off_by_one" in self.mutants and depth != UNBOUNDED:
            depth += 1
        self.max_depth = depth
        self.light_samples = light_samples
        self.rr_depth = rr_depth
        light = geometry.scene.light
        self.light_area = light.area
        self.light_radiance = light.radiance
        self.has_mirror = geometry.has(KIND_MIRROR)
        self.has_diffuse = geometry.has(KIND_LAMBERTIAN)
        # Whether light found by a diffuse bounce counts: only then does a
        # path whose last vertex is diffuse need its final segment traced.
        self.diffuse_sees_emission = mis or geometry.has_surface_emission() or "double_count" in self.mutants

    # ------------------------------------------------------------------
    @dr.syntax
    def path_sums(self, camera_ray, rng, paths):
        """Sums of x and x^2 over ``paths`` radiance samples x traced in turn by each lane.

        A lane traces one camera path after another (path regeneration):
        where a path ends, its sample x is added to the lane's sums and the
        lane starts its next path in the same loop iteration. A 16-lane packet
        then runs until its lanes' total work is done, instead of until its
        longest single path ends; after the first roulette most packets
        would otherwise carry mostly finished lanes.

        The camera jitter of a new path reuses the two numbers that the
        ended path drew for its next direction: a path ends at the light,
        at the depth limit or by roulette, none of which depends on those
        numbers, and the ended path never traced that direction, so they
        are independent of everything its sample used.

        ``camera_ray(u, v)`` gives the ray (o, d) through the lane's pixel
        at jitter (u, v), d of unit length; ``paths`` (UInt32) counts the
        lane's paths, at least one. Returns (sum x, sum x^2), Array3f.
        """
        m, geo = self.m, self.geo

        # ---- Loop state.
        o, d = camera_ray(rng.next_float32(), rng.next_float32())  # the current ray
        L = m.Array3f(0.0)  # radiance of the current path gathered so far
        beta = m.Array3f(1.0)  # path throughput: product of f cos / pdf so far
        depth = m.UInt32(0)  # segments of the current path traced so far
        specular = m.Bool(True)  # the last vertex was the eye or a mirror: count emission
        pdf_bsdf = m.Float(0.0)  # solid-angle pdf of the last diffuse direction (for MIS)
        sum_x = m.Array3f(0.0)  # the lane's finished samples: sum of x
        sum_x2 = m.Array3f(0.0)  # and of x^2
        left = m.UInt32(paths - 1)  # paths the lane has still to start
        active = m.Bool(True)  # the lane has a path in flight

        while dr.hint(active, label="mcrt_path"):
            t, sid, n = geo.intersect(o, d)
            depth += 1
            p = dr.fma(d, t, o)
            is_light = sid == geo.light_id

            # ---- Emission seen from the eye or through mirrors.
            L = dr.fma(beta, self.emitted(d, t, is_light, specular, pdf_bsdf), L)
            if geo.has_surface_emission():
                L = dr.fma(beta, self.surface_emitted(d, n, sid), L)

            # ---- Stop at the light (black on both sides) and at the depth limit.
            alive = ~is_light & (depth < self.max_depth)
            if not geo.normals_face_ray:
                n = dr.select(dr.dot(d, n) < 0, n, -n)  # two-sided triangles: the normal on the arriving side
            origin = self.spawn_origin(p, n)
            mirror = self.is_mirror(sid)
            diffuse = alive & ~mirror  # the light has stopped the path already
            if not self.diffuse_sees_emission:
                # The last segment after a diffuse vertex could only find emission,
                # which the light sample here has already counted: end the path.
                alive &= mirror | (depth + 1 < self.max_depth)
            color = self.surface_color(sid)

            # ---- Next-event estimation at diffuse vertices (depth + 1 <= max_depth holds here).
            L = dr.fma(beta * color, self.direct_light(origin, n, rng, diffuse), L)

            # ---- Continue: cosine-weighted Lambertian direction or mirror reflection.
            u1, u2 = rng.next_float32(), rng.next_float32()
            d, weight, specular = self.scatter(d, n, color, alive & mirror, u1, u2, rng)
            if self.mis:
                pdf_bsdf = dr.maximum(dr.dot(n, d), 0.0) * INV_PI
            beta *= weight
            o = origin

            # ---- Russian roulette.
            beta, alive = self.roulette(beta, depth, diffuse, alive, rng)

            # ---- A path that ended is added to the sums; its lane starts the next one.
            ended = ~alive
            sum_x = dr.select(ended, sum_x + L, sum_x)
            sum_x2 = dr.select(ended, dr.fma(L, L, sum_x2), sum_x2)
            restart = ended & (left > 0)
            left = dr.select(restart, left - 1, left)
            o_new, d_new = camera_ray(u1, u2)
            o = dr.select(restart, o_new, o)
            d = dr.select(restart, d_new, d)
            L = dr.select(ended, 0.0, L)
            beta = dr.select(restart, 1.0, beta)
            depth = dr.select(restart, 0, depth)
            specular |= restart
            active = alive | restart
        return sum_x, sum_x2

    # ------------------------------------------------------------------
    def emitted(self, d, t, is_light, specular, pdf_bsdf):
        """Le towards -d where a ray meets the light's emitting side, weighted for light sampling.

        Without MIS: counted only where no light sample could have found it
        (from the eye, after a mirror). With MIS, a hit after a diffuse bounce
        counts too, with the balance weight of BSDF sampling against K light
        samples, w_b = p_b / (K p_l + p_b), p_l = t^2 / (A cos_y).
        """
        m, mut = self.m, self.mutants
        radiance = m.Array3f(*self.light_radiance)
        cos_y = -d.z * self.geo.light_normal_z  # the light is horizontal: n = (0, 0, n_z)
        faces_ray = cos_y > 0
        if "light_two_sided" in mut:
            faces_ray = m.Bool(True)
            cos_y = dr.abs(cos_y)
        if "double_count" in mut:
            return dr.select(is_light & faces_ray, radiance, 0.0)
        if not self.mis:
            return dr.select(is_light & faces_ray & specular, radiance, 0.0)
        a = pdf_bsdf * self.light_area * cos_y
        w_bsdf = dr.select(specular, 1.0, a / (self.light_samples * t * t + a))
        return dr.select(is_light & faces_ray, radiance * w_bsdf, 0.0)

    def surface_color(self, sid):
        """Albedo, reflectance or radiance of surface ``sid``.

        A chain of selects over the scene's dozen surfaces: measured faster
        here than three gathers from a table.
        """
        m = self.m
        out = [m.Float(0.0), m.Float(0.0), m.Float(0.0)]
        for k, srf in enumerate(self.geo.surfaces):
            hit = sid == k
            out = [dr.select(hit, float(srf.color[c]), out[c]) for c in range(3)]
        return m.Array3f(*out)

    def surface_emitted(self, d, n, sid):
        """Emission of Lambertian surfaces (furnace scenes), on the side their normal faces.

        No light sample ever reaches these surfaces, so every hit counts it.
        A select per emitting surface, like :meth:`surface_color`: a table
        would be copied to the device inside the traced pass, which a frozen
        pass (mcrt.tracer.Tracer.pass_sums) cannot record.
        """
        m = self.m
        out = [m.Float(0.0), m.Float(0.0), m.Float(0.0)]
        for k, srf in enumerate(self.geo.surfaces):
            if any(srf.emission):
                hit = sid == k
                out = [dr.select(hit, float(srf.emission[c]), out[c]) for c in range(3)]
        return dr.select(dr.dot(d, n) < 0, m.Array3f(*out), 0.0)

    def spawn_origin(self, p, n):
        """The origin of rays leaving p on the side of n, offset against self-intersection."""
        if "no_offset" in self.mutants:
            return p
        return dr.fma(n, self.geo.offset(p), p)

    def is_mirror(self, sid):
        """Whether surface ``sid`` is a mirror: a comparison per mirror surface (none without mirrors)."""
        mirror = self.m.Bool(False)
        for k, s in enumerate(self.geo.surfaces):
            if s.kind == KIND_MIRROR:
                mirror |= sid == k
        return mirror

    def scatter(self, d, n, color, mirror, u1, u2, rng):
        """Next direction from (u1, u2), weight f cos / pdf, and whether the bounce was specular (at a mirror)."""
        m = self.m
        d_next, weight = self.sample_lambertian(n, color, u1, u2, rng)
        if not self.has_mirror:
            return d_next, weight, m.Bool(False)
        r = dr.fma(-2.0 * dr.dot(d, n), n, d)  # perfect reflection about n
        if "mirror_wrong_sign" in self.mutants:
            r = -r
        return dr.select(mirror, r, d_next), dr.select(mirror, color, weight), mirror

    def roulette(self, beta, depth, diffuse, active, rng):
        """Unbiased Russian roulette: survive with q = min(max beta, 0.95), then beta /= q."""
        if "rr_no_divide" in self.mutants:
            survive = rng.next_float32() >= 0.75
            return dr.select(diffuse, beta * 0.8, beta), active & (~diffuse | survive)
        q = dr.minimum(_max3(beta), 0.95)
        roulette = active & (depth >= self.rr_depth)
        survive = rng.next_float32() < q
        return dr.select(roulette, beta * dr.rcp(q), beta), active & (~roulette | survive)

    def sample_lambertian(self, n, albedo, u1, u2, rng):
        """A direction about n from (u1, u2) and its weight f cos / pdf (= albedo for the cosine warp)."""
        m, mut = self.m, self.mutants
        weight = albedo * math.pi if "brdf_no_inv_pi" in mut else albedo
        if "ball_plus_normal" in mut:
            b = square_to_uniform_ball(u1, u2, rng.next_float32())
            return dr.normalize(m.Array3f(*b) + n), weight
        if "uniform_as_cosine" not in mut:
            return m.Array3f(*cosine_about_normal(u1, u2, (n.x, n.y, n.z))), weight
        local = square_to_uniform_hemisphere(u1, u2)
        s, t = coordinate_frame(n.x, n.y, n.z)
        return m.Array3f(*to_world(local, s, t, (n.x, n.y, n.z))), weight

    # ------------------------------------------------------------------
    def direct_light(self, origin, n, rng, active):
        """(1/pi) (1/K) sum_k Le V cos_x cos_y / d^2 * A: the direct light over the albedo.

        Points y_k are uniform on the light (pdf_area 1/A); the shadow ray
        stops just short of y_k. K = 1 traces no loop.
        """
        if not self.has_diffuse:
            return self.m.Array3f(0.0)
        f = 1.0 if "brdf_no_inv_pi" in self.mutants else INV_PI
        if self.light_samples == 1:
            return self.light_sample(origin, n, rng, active) * f
        return self._light_sample_loop(origin, n, rng, active) * (f / self.light_samples)

    @dr.syntax
    def _light_sample_loop(self, origin, n, rng, active):
        acc = self.m.Array3f(0.0)
        k = self.m.UInt32(0)
        while dr.hint(active & (k < self.light_samples), label="mcrt_light_samples"):
            acc += self.light_sample(origin, n, rng, active)
            k += 1
        return acc

    def light_sample(self, origin, n, rng, active):
        """One light sample: Le V cos_x cos_y / d^2 / pdf_area, with pdf_area = 1/A."""
        m, geo, mut = self.m, self.geo, self.mutants
        cx, cy, cz = geo.light_center
        hx, hy = geo.light_half
        u1, u2 = rng.next_float32(), rng.next_float32()
        y = m.Array3f(dr.fma(u1, 2.0 * hx, cx - hx), dr.fma(u2, 2.0 * hy, cy - hy), cz)
        wi = y - origin
        dist2 = dr.squared_norm(wi)
        inv_dist = dr.rsqrt(dist2)
        wi *= inv_dist
        cos_x = dr.dot(n, wi)
        cos_y = -wi.z * geo.light_normal_z
        if "light_two_sided" in mut:
            cos_y = dr.abs(cos_y)
        valid = active & (cos_x > 0) & (cos_y > 0)
        g = (1.0 if "nee_no_cos_surface" in mut else cos_x) * (1.0 if "nee_no_cos_light" in mut else cos_y)
        if "nee_no_inv_dist2" not in mut:
            g = g * dr.square(inv_dist)
        if "shadow_unbounded" in mut:
            blocked = geo.occluded(origin, wi, m.Float(dr.inf), include_room=True)
        else:
            blocked = geo.occluded(origin, wi, dist2 * inv_dist * SHADOW_TMAX_SCALE, active=valid)
        area = 1.0 if "nee_no_area" in mut else self.light_area
        if self.mis:
            # Balance weight of K light samples against the cosine BSDF sample:
            # w_l = K p_l / (K p_l + p_b), p_l = d^2 / (A cos_y), p_b = cos_x / pi.
            k_d2 = self.light_samples * dist2
            g = g * (k_d2 / (k_d2 + cos_x * INV_PI * self.light_area * cos_y))
        return dr.select(valid & ~blocked, m.Array3f(*self.light_radiance) * (g * area), 0.0)
