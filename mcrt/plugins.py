r"""Mitsuba 3 plugins: mcrt's estimator as the Mitsuba integrator ``mcrt``.

The integrator is :class:`mcrt.estimator.PathEstimator`, the very code of
the standalone tracer, on a second host: :class:`MitsubaHost` answers the
estimator's questions (closest hit, light sample, occlusion, material,
spawned ray) with Mitsuba's ``ray_intersect``, emitter sampling,
``ray_test`` and BSDFs. With it a render can be compared three ways:

===========================  ===================  ===============
renderer (mcrt.render)       geometry/intersect.  estimator
===========================  ===================  ===============
``mcrt``                     mcrt                 mcrt
``plugin``                   Mitsuba              mcrt
``mitsuba``                  Mitsuba              Mitsuba ``path``
===========================  ===================  ===============

so a disagreement between the standalone tracer and the plugin comes from
geometry and intersection, and one between the plugin and Mitsuba's ``path``
from the estimator.

No sensor plugin is needed: Mitsuba's ``perspective`` sensor (``fov_axis``
x, ``look_at`` eye -> eye + forward, up, ``box`` filter) reproduces the
pinhole mapping of scene.md exactly; ``tests/test_mitsuba.py`` checks the
rays it generates against :mod:`mcrt.camera`.

Loading
-------
Mitsuba's classes exist only once a variant is chosen, so registration
happens then: ``import mcrt.plugins`` registers ``mcrt`` at once when a
variant is already set, and installs a variant callback that registers it
again whenever ``mi.set_variant`` is called later. :func:`register` does the
same by hand (idempotent)::

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    import mcrt.plugins                    # registers the integrator 'mcrt'
    scene = mi.load_dict({..., "integrator": {"type": "mcrt", "max_depth": 8, "light_samples": 4}})
    image = mi.render(scene, spp=64)

or in XML: ``<integrator type="mcrt"><integer name="max_depth" value="8"/>
<integer name="light_samples" value="4"/></integrator>``. Mitsuba has no
entry-point discovery of Python plugins; the import is the loading step.

Parameters
----------
max_depth : int
    Longest path in segments, as Mitsuba's ``path`` counts it: 1 shows
    emitters seen directly, 2 adds direct light; -1 is unbounded. Default 8.
light_samples : int
    K, shadow rays per diffuse vertex. Default 1.
rr_depth : int
    Depth from which Russian roulette runs. Default 5.
hide_emitters : bool
    Do not count emitters seen directly from the sensor. Default false.
mis : bool
    Combine light samples and cosine directions by the balance heuristic
    (for a light that touches a surface). Default false.
mutant : str
    Comma-separated names of the estimator's catalogued bugs
    (:data:`mcrt.mutants.MUTANTS` whose options are the estimator's), for
    testing the tests. Default empty. The camera, output and scene bugs
    (``no_jitter``, ``gamma_output``, ``albedo_1pct``) are not the
    integrator's: :func:`render_plugin` applies them around it.

Scenes
------
The estimator knows Lambertian surfaces, perfect mirrors and area lights,
so :func:`check_scene` accepts BSDFs ``diffuse``, ``twosided`` around
``diffuse`` (or around a perfect mirror), ``conductor`` with Fresnel
reflectance 1 (material ``none``, i.e. eta 0 and k 1), and ``area``
emitters, on any shapes; anything else (``roughconductor``, ``dielectric``,
``plastic``, ``point``, ``envmap``, media, ...) is refused with a one-line
``ValueError`` naming the offending plugin. The integrator checks its scene
on the first call of :meth:`sample` for that scene; under ``mi.render`` the
error arrives as the cause of Mitsuba's ``RuntimeError``.

Variants: the JIT variants (tested in ``llvm_ad_rgb``; ``cuda_ad_rgb`` runs
the same code). Polarized variants are not supported.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

from mcrt.estimator import EstimatorOptions, Hit, PathEstimator
from mcrt.film import RenderResult
from mcrt.imageio import encode_output
from mcrt.light import LightSample, needs_mis
from mcrt.mitsuba import _use, render_mitsuba
from mcrt.mutants import CATALOGUE, camera_jitter, check_mutants, estimator_overrides, mutate_scene, output_encoding
from mcrt.scene import RenderSettings, Scene

__all__ = ["MitsubaHost", "McrtIntegrator", "check_scene", "integrator_class", "parse_mutants", "register", "render_plugin"]

#: Name under which the integrator is registered.
NAME = "mcrt"

# Class names of Mitsuba plugins -> their plugin names, for error messages.
_PLUGIN_NAMES = {
    "SmoothDiffuse": "diffuse", "TwoSidedBRDF": "twosided", "SmoothConductor": "conductor",
    "RoughConductor": "roughconductor", "SmoothDielectric": "dielectric", "RoughDielectric": "roughdielectric",
    "ThinDielectric": "thindielectric", "SmoothPlastic": "plastic", "RoughPlastic": "roughplastic",
    "PolarizedPlastic": "pplastic", "Principled": "principled", "PrincipledThin": "principledthin",
    "BlendBSDF": "blendbsdf", "MaskBSDF": "mask", "BumpMap": "bumpmap", "NormalMap": "normalmap",
    "Measured": "measured", "MeasuredPolarized": "measured_polarized", "Hair": "hair", "Null": "null",
    "AreaLight": "area", "PointLight": "point", "SpotLight": "spot", "DirectionalEmitter": "directional",
    "DirectionalArea": "directionalarea", "ConstantBackgroundEmitter": "constant",
    "EnvironmentMapEmitter": "envmap", "Projector": "projector", "SunskyEmitter": "sunsky",
}


def _plugin(obj) -> str:
    """'name' (ClassName) of a Mitsuba object for messages."""
    cls = obj.class_name()
    name = _PLUGIN_NAMES.get(cls)
    return f"'{name}' ({cls})" if name else f"{cls}"


# --------------------------------------------------------------------------
# Mutants
# --------------------------------------------------------------------------


def parse_mutants(spec) -> frozenset[str]:
    """Mutant names from a comma-separated string or an iterable: the estimator's bugs only.

    Raises a one-line ``ValueError`` for an unknown name and for a bug of the
    camera, the output or the scene, which the integrator cannot apply
    (:func:`render_plugin` does).
    """
    if isinstance(spec, str):
        spec = [s.strip() for s in spec.split(",")]
    names = check_mutants(s for s in spec if s)
    other = sorted(n for n in names if not CATALOGUE[n].estimator)
    if other:
        raise ValueError(
            f"mcrt integrator: mutant {other[0]!r} changes the camera, the output or the scene, not the estimator: "
            f"render with mcrt.render.render(..., renderer='plugin', mutants=...) instead"
        )
    return names


# --------------------------------------------------------------------------
# Scene check
# --------------------------------------------------------------------------


def _params(obj) -> dict[str, Any]:
    return {k: v for k, v in mi.traverse(obj).items()}


def _is_perfect_mirror(params: dict[str, Any], prefix: str = "") -> bool:
    """A smooth conductor whose Fresnel term is 1: eta 0 and k 1 as constants (material 'none')."""
    eta, k = params.get(prefix + "eta.value"), params.get(prefix + "k.value")
    if eta is None or k is None:
        return False
    return bool(dr.all(dr.ravel(eta) == 0, axis=None)) and bool(dr.all(dr.ravel(k) == 1, axis=None))


def _check_bsdf(bsdf, where: str) -> None:
    cls = bsdf.class_name()
    flags = [int(bsdf.flags(i)) for i in range(bsdf.component_count())]
    F = mi.BSDFFlags
    diffuse = all((f & int(F.All)) == int(F.DiffuseReflection) for f in flags)
    delta = all((f & int(F.All)) == int(F.DeltaReflection) for f in flags)
    ok = False
    if cls == "SmoothDiffuse":
        ok = True
    elif cls == "SmoothConductor":
        ok = _is_perfect_mirror(_params(bsdf))
        if not ok:
            raise ValueError(
                f"mcrt integrator: {where} has a 'conductor' that is not a perfect mirror "
                f"(use material 'none': mcrt's mirror has no Fresnel term)"
            )
    elif cls == "TwoSidedBRDF":
        # The nested BSDFs are not reachable from Python; their components and
        # parameters are: only 'reflectance' (diffuse) or eta/k/specular_reflectance (mirror).
        params = _params(bsdf)
        if diffuse:
            ok = all(k.split(".", 1)[1].startswith("reflectance") for k in params)
        elif delta:
            ok = all(_is_perfect_mirror(params, f"brdf_{i}.") for i in (0, 1) if f"brdf_{i}.eta.value" in params) and any(
                k.endswith("eta.value") for k in params
            )
    if not ok:
        raise ValueError(
            f"mcrt integrator: {where} has BSDF {_plugin(bsdf)}, which mcrt's estimator does not model "
            f"(supported: 'diffuse', 'twosided' diffuse, 'conductor' with material 'none')"
        )


def check_scene(scene: "mi.Scene") -> None:
    """Raise a one-line ``ValueError`` unless ``scene`` holds only what mcrt's estimator models.

    Accepted: shapes with BSDF ``diffuse``, ``twosided`` (around ``diffuse``
    or a perfect mirror) or ``conductor`` with Fresnel reflectance 1
    (material ``none``); emitters of type ``area``; no participating media.
    The message names the offending plugin and shape.
    """
    for shape in scene.shapes():
        where = f"shape '{shape.id()}'"
        if shape.is_medium_transition():
            raise ValueError(f"mcrt integrator: {where} bounds a participating medium, which mcrt's estimator does not model")
        bsdf = shape.bsdf()
        if bsdf is not None:
            _check_bsdf(bsdf, where)
    for emitter in scene.emitters():
        if emitter.class_name() != "AreaLight":
            raise ValueError(
                f"mcrt integrator: emitter '{emitter.id()}' is of type {_plugin(emitter)}; "
                f"mcrt's estimator supports only 'area' emitters"
            )


# --------------------------------------------------------------------------
# The estimator's host on a Mitsuba scene
# --------------------------------------------------------------------------


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
        if not (isinstance(tmax, float) and tmax == dr.inf):
            ray.maxt = tmax
        return self.scene.ray_test(ray, active)

    def spawn_origin(self, hit):
        return dr.fma((1.0 + dr.max(dr.abs(hit.p))) * mi.math.RayEpsilon, hit.n, hit.p)


# --------------------------------------------------------------------------
# The integrator (one class per Mitsuba variant)
# --------------------------------------------------------------------------


def _define_class():
    """Define McrtIntegrator against the current variant's mi.SamplingIntegrator."""

    class McrtIntegrator(mi.SamplingIntegrator):
        """mcrt's estimator (:class:`mcrt.estimator.PathEstimator`) on :class:`MitsubaHost`."""

        def __init__(self, props):
            super().__init__(props)
            try:
                self.options = EstimatorOptions(
                    max_depth=int(props.get("max_depth", 8)), light_samples=int(props.get("light_samples", 1)),
                    rr_depth=int(props.get("rr_depth", 5)), mis=bool(props.get("mis", False)),
                    hide_emitters=self.hide_emitters, **estimator_overrides(parse_mutants(props.get("mutant", ""))),
                )
            except ValueError as e:
                raise ValueError(str(e) if str(e).startswith("mcrt integrator:") else f"mcrt integrator: {e}") from None
            self.mutants = parse_mutants(props.get("mutant", ""))

        def to_string(self) -> str:
            o = self.options
            mut = f", mutant='{','.join(sorted(self.mutants))}'" if self.mutants else ""
            return (f"McrtIntegrator[max_depth={o.max_depth}, light_samples={o.light_samples}, rr_depth={o.rr_depth}, "
                    f"mis={o.mis}, hide_emitters={o.hide_emitters}{mut}]")

        def aov_names(self):
            return []

        def sample(self, scene, sampler, ray, medium=None, active=True):
            """One radiance sample per ray: (spectrum, valid, aovs)."""
            check_scene(scene)  # about 1 ms, once per traced kernel
            estimator = PathEstimator(MitsubaHost(scene), self.options)
            L, _, valid = estimator.path_sums(mi.Point3f(ray.o), mi.Vector3f(ray.d), sampler, active=mi.Bool(active))
            return L, valid, []

    return McrtIntegrator


_CLASSES: dict[str, type] = {}


def integrator_class() -> type:
    """The McrtIntegrator class of the current Mitsuba variant (defined on first use)."""
    variant = mi.variant()
    if variant is None:
        raise RuntimeError("mcrt.plugins: set a Mitsuba variant first (mi.set_variant('llvm_ad_rgb'))")
    if variant not in _CLASSES:
        if "polarized" in variant:
            raise RuntimeError(f"mcrt.plugins: the mcrt integrator does not support polarized variants ({variant})")
        _CLASSES[variant] = _define_class()
    return _CLASSES[variant]


def register() -> None:
    """Register the integrator ``mcrt`` with Mitsuba in the current variant (idempotent).

    Called on ``import mcrt.plugins`` when a variant is set, and on every
    later ``mi.set_variant`` through a variant callback; call it yourself
    only if that callback was removed (``mi.detail.clear_variant_callbacks``).
    """
    if mi.variant() is None:
        raise RuntimeError("mcrt.plugins.register: set a Mitsuba variant first (mi.set_variant('llvm_ad_rgb'))")
    if "polarized" in mi.variant():
        return
    mi.register_integrator(NAME, lambda props: integrator_class()(props))


def _on_variant_change(old, new) -> None:
    if new is not None and "polarized" not in new:
        register()


def __getattr__(name: str):
    # mcrt.plugins.McrtIntegrator: the class of the current variant.
    if name == "McrtIntegrator":
        return integrator_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


mi.detail.add_variant_callback(_on_variant_change)
if mi.variant() is not None:
    register()


# --------------------------------------------------------------------------
# Rendering an mcrt Scene with the plugin
# --------------------------------------------------------------------------


def render_plugin(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                  spp_per_pass: int | None = None, mutants=(), mis: bool | None = None) -> RenderResult:
    """Render ``scene`` at ``settings`` with the ``mcrt`` integrator inside Mitsuba: mean and per-sample variance.

    Called through :func:`mcrt.render.render` (renderer ``plugin``). The
    scene, sensor and passes are those of :func:`mcrt.mitsuba.render_mitsuba`;
    only the integrator differs. Every catalogued mutant runs: the
    estimator's inside the integrator, the camera's (jitter) in the passes,
    the output's on the image and the scene's on the scene. ``mis`` as in the
    standalone tracer (default: where the scene needs it). The result has
    ``renderer='mitsuba-mcrt'``.
    """
    names = check_mutants(mutants)
    mutated = mutate_scene(scene, names)
    use_mis = needs_mis(mutated) if mis is None else bool(mis)
    _use(backend)
    register()
    integrator = {"type": NAME, "light_samples": int(settings.light_samples), "mis": use_mis,
                  "mutant": ",".join(sorted(n for n in names if CATALOGUE[n].estimator))}
    r = render_mitsuba(mutated, settings, backend=backend, progress=progress, spp_per_pass=spp_per_pass,
                       integrator=integrator, jitter=camera_jitter(names))
    mean, var = encode_output(r.mean, r.variance, output_encoding(names))
    extra = dict(r.extra, light_samples=str(settings.light_samples), mis=str(use_mis).lower(), mutants=",".join(sorted(names)))
    return dataclasses.replace(r, mean=mean, variance=var, renderer="mitsuba-mcrt", scene_hash=scene.content_hash(), extra=extra)
