"""mcrt's own scene as a host of the estimator (:mod:`mcrt.estimator`).

The host turns :mod:`mcrt.geometry`'s closest hits (a distance and a surface
id) into what the estimator asks for: the hit point and the normal on the
ray's side, the surface's material, and the light's emission; light samples
come from :class:`mcrt.light.RectangleLight`. Everything the scene holds is a
constant of the kernel, and what it lacks is not traced at all: no mirror
code without a mirror, no emission lookups unless a surface emits.
"""

from __future__ import annotations

import drjit as dr

from mcrt.estimator import Hit
from mcrt.geometry import KIND_LAMBERTIAN, KIND_MIRROR, Geometry
from mcrt.light import RectangleLight


class McrtHost:
    """The estimator's host (:class:`mcrt.estimator.Host`, with solid-angle light sampling) on a
    :class:`mcrt.geometry.Geometry` of backend ``geometry.m``.

    ``light`` (:class:`mcrt.light.RectangleLight`) is the scene's light, for
    :mod:`mcrt.bidir`'s light tracer too.
    """

    rays_escape = False  # the room is closed: every ray hits something

    def __init__(self, geometry: Geometry):
        self.geo = geometry
        m = geometry.m
        self.m = m
        self.Float, self.UInt32, self.Bool = m.Float, m.UInt32, m.Bool
        self.Vector3f = self.Spectrum = m.Array3f
        self.light = RectangleLight(geometry.scene.light, m)
        self.has_mirror = geometry.has(KIND_MIRROR)
        self.has_diffuse = geometry.has(KIND_LAMBERTIAN)
        self.has_unsampled_emission = geometry.has_surface_emission()

    # ------------------------------------------------------------------
    def intersect(self, o, d, active=True) -> Hit:
        """The closest hit of rays (o, d), d of unit length."""
        geo = self.geo
        t, sid, n = geo.intersect(o, d)
        emission = self.surface_emitted(d, n, sid) if self.has_unsampled_emission else None
        if not geo.normals_face_ray:
            n = dr.select(dr.dot(d, n) < 0, n, -n)  # two-sided triangles: the normal on the arriving side
        light = sid == geo.light_id
        return Hit(
            t=t, p=dr.fma(d, t, o), n=n, reflects=~light, mirror=self.is_mirror(sid), color=self.surface_color(sid),
            light=light, light_cos=self.light.cos_toward(d), light_radiance=self.light.emitted(), emission=emission,
        )

    def sample_light(self, x, u1, u2, active=True):
        """A point uniform on the light (pdf_area 1/A), seen from x."""
        return self.light.sample(x, u1, u2)

    def sample_light_solid_angle(self, x, u1, u2, active=True):
        """A point on the light uniform in its solid angle seen from x (pdf_area cos_y / (d^2 Omega))."""
        return self.light.sample_solid_angle(x, u1, u2)

    def light_pdf_area(self, hit, active=True):
        """The area density of the light sample at a hit light point: 1/A."""
        return self.light.pdf_area

    def occluded(self, o, d, tmax, active=True):
        """Whether an object blocks o + t d, 0 < t < tmax; tmax None also tests the room (it always blocks)."""
        if tmax is None:
            return self.geo.occluded(o, d, self.m.Float(dr.inf), include_room=True)
        return self.geo.occluded(o, d, tmax, active=active)

    def spawn_origin(self, hit):
        """p moved off the surface along the arriving side's normal by :meth:`mcrt.geometry.Geometry.offset`."""
        return self.offset_along(hit.p, hit.n)

    def offset_along(self, p, n):
        """p moved along the unit vector n by :meth:`mcrt.geometry.Geometry.offset` (rays leaving a surface start there)."""
        return dr.fma(n, self.geo.offset(p), p)

    # ------------------------------------------------------------------
    def surface_color(self, sid):
        """Albedo or reflectance of surface ``sid``.

        A chain of selects over the scene's dozen surfaces, chosen over three
        gathers from a table because it was faster in this kernel.
        """
        m = self.m
        out = [m.Float(0.0), m.Float(0.0), m.Float(0.0)]
        for k, srf in enumerate(self.geo.surfaces):
            if srf.kind == KIND_LAMBERTIAN or srf.kind == KIND_MIRROR:
                hit = sid == k
                out = [dr.select(hit, float(srf.color[c]), out[c]) for c in range(3)]
        return m.Array3f(*out)

    def is_mirror(self, sid):
        """Whether surface ``sid`` is a mirror: a comparison per mirror surface (none without mirrors)."""
        mirror = self.m.Bool(False)
        for k, s in enumerate(self.geo.surfaces):
            if s.kind == KIND_MIRROR:
                mirror |= sid == k
        return mirror

    def surface_emitted(self, d, n, sid):
        """Emission of Lambertian surfaces (furnace scenes), on the side their normal faces.

        No light sample reaches these surfaces, so every hit counts it. A
        select per emitting surface, like :meth:`surface_color`: a table
        would be copied to the device inside the traced pass, which a frozen
        pass (:meth:`mcrt.tracer.Tracer.pass_sums`) cannot record.
        """
        m = self.m
        out = [m.Float(0.0), m.Float(0.0), m.Float(0.0)]
        for k, srf in enumerate(self.geo.surfaces):
            if any(srf.emission):
                hit = sid == k
                out = [dr.select(hit, float(srf.emission[c]), out[c]) for c in range(3)]
        return dr.select(dr.dot(d, n) < 0, m.Array3f(*out), 0.0)
