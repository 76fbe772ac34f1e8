"""The estimator's host (:mod:`mcrt.estimator`) on a Mitsuba scene."""

from __future__ import annotations

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

from mcrt.estimator import Hit
from mcrt.light import LightSample


class MitsubaHost:
    """The estimator's host (:mod:`mcrt.estimator`) on a loaded ``mi.Scene`` of the current variant.

    - Closest hit: ``scene.ray_intersect``; the normal is the geometric one,
      turned to the side the ray arrived from. The material comes from the
      shape's BSDF: a delta BSDF is a mirror, whose reflectance is the
      weight of its (deterministic) sample; otherwise the BSDF's diffuse
      reflectance is the albedo, zero on the back of a one-sided BSDF.
    - Light samples: ``scene.sample_emitter`` chooses an emitter (probability
      p_sel), its ``sample_position`` a point with area density p_pos;
      pdf_area = p_sel p_pos, and the radiance is ``emitter.eval`` seen from
      the emitting side.
    - Occlusion: ``scene.ray_test`` of the segment.
    - Spawned rays: offset along the normal by Mitsuba's own rule,
      RayEpsilon (1 + max |p_i|).

    Every emitter is an area emitter that next-event estimation samples, so
    no emission goes unsampled.
    """

    rays_escape = True
    has_unsampled_emission = False

    def __init__(self, scene: "mi.Scene"):
        self.scene = scene
        self.Float, self.UInt32, self.Bool = mi.Float, mi.UInt32, mi.Bool
        self.Vector3f, self.Spectrum = mi.Vector3f, mi.Spectrum
        flags = [int(s.bsdf().flags()) for s in scene.shapes() if s.bsdf() is not None]
        self.has_mirror = any(f & int(mi.BSDFFlags.Delta) for f in flags)
        self.has_diffuse = any(f & int(mi.BSDFFlags.DiffuseReflection) for f in flags)

    def intersect(self, o, d, active=True) -> Hit:
        ray = mi.Ray3f(o, d)
        si = self.scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=False, active=active)
        valid = active & si.is_valid()
        bsdf = si.bsdf(ray)
        flags = bsdf.flags()
        mirror = valid & mi.has_flag(flags, mi.BSDFFlags.Delta)
        back = mi.Frame3f.cos_theta(si.wi) < 0
        one_sided = ~mi.has_flag(flags, mi.BSDFFlags.BackSide)
        albedo = bsdf.eval_diffuse_reflectance(si, valid & ~mirror)
        color = dr.select(back & one_sided, 0.0, albedo)
        if self.has_mirror:
            _, reflectance = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.5), mirror)
            color = dr.select(mirror, reflectance, color)
        light = valid & si.shape.is_emitter()
        n = mi.Vector3f(si.n)  # a Normal3f would change the type of the estimator's direction
        front = mi.SurfaceInteraction3f(si)
        front.wi = mi.Vector3f(si.wi.x, si.wi.y, dr.abs(si.wi.z))  # the emitting side, wherever the ray came from
        return Hit(
            t=si.t, p=si.p, n=dr.select(dr.dot(d, si.n) < 0, n, -n), reflects=valid & (dr.max(color) > 0),
            mirror=mirror, color=color, light=light, light_cos=mi.Frame3f.cos_theta(si.wi),
            light_radiance=si.emitter(self.scene, light).eval(front, light), valid=valid, extra=(si, o),
        )

    def sample_light(self, x, u1, u2, active=True) -> LightSample:
        index, inv_p_sel, u1 = self.scene.sample_emitter(u1, active)
        emitter = dr.gather(mi.EmitterPtr, self.scene.emitters_dr(), index, active)
        ps, _ = emitter.sample_position(0.0, mi.Point2f(u1, u2), active)
        seen = mi.SurfaceInteraction3f(ps, dr.zeros(mi.Color0f))
        seen.wi = mi.Vector3f(0.0, 0.0, 1.0)  # the emitting side
        wi = ps.p - x
        dist2 = dr.squared_norm(wi)
        inv_dist = dr.rsqrt(dist2)
        wi = wi * inv_dist
        return LightSample(wi, dist2, inv_dist, -dr.dot(ps.n, wi), emitter.eval(seen, active), ps.pdf / inv_p_sel)

    def light_pdf_area(self, hit, active=True):
        """p_sel p_pos of the hit light point, from Mitsuba's solid-angle density seen from the ray's origin."""
        si, o = hit.extra
        ref = dr.zeros(mi.Interaction3f)
        ref.p = o
        ds = mi.DirectionSample3f(self.scene, si, ref)
        return self.scene.pdf_emitter_direction(ref, ds, active) * dr.abs(dr.dot(ds.d, ds.n)) / dr.square(ds.dist)

    def occluded(self, o, d, tmax, active=True):
        ray = mi.Ray3f(o, d)
        if tmax is not None:
            ray.maxt = tmax
        return self.scene.ray_test(ray, active)

    def spawn_origin(self, hit):
        return dr.fma((1.0 + dr.max(dr.abs(hit.p))) * mi.math.RayEpsilon, hit.n, hit.p)
