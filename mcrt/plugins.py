r"""Mitsuba 3 plugins: mcrt's estimator as the Mitsuba integrator ``mcrt``.

The integrator computes exactly the estimator of :mod:`mcrt.integrator`
(Lambertian + mirror path tracing with next-event estimation, K light samples
per diffuse vertex, the same Russian roulette and maximum-depth rule), but on
top of Mitsuba's own ray intersection, BSDFs and emitter sampling. With it a
render can be compared three ways:

===========================  ===================  ===============
                             geometry/intersect.  estimator
===========================  ===================  ===============
``mcrt.tracer.render``       mcrt                 mcrt
:func:`render_plugin`        Mitsuba              mcrt
``mcrt.mitsuba.render_...``  Mitsuba              Mitsuba ``path``
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
mutant : str
    Comma-separated names from :data:`mcrt.mutants.MUTANTS` (those in
    :data:`INTEGRATOR_MUTANTS`), the estimator bugs of the tracer, for
    testing the tests. Default empty. Each has the tracer's expected image
    except ``no_offset``, whose self-intersections are Mitsuba's own.

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

Variants: tested in ``llvm_ad_rgb``; it also runs in ``llvm_ad_spectral``,
``llvm_ad_mono`` and (very slowly, one Python call per ray) ``scalar_rgb``.
``cuda_ad_rgb`` uses the same code but was not run here (no GPU).
Polarized variants are not supported.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import drjit as dr
import mitsuba as mi

from mcrt.film import RenderResult
from mcrt.mitsuba import _use, render_mitsuba
from mcrt.mutants import MUTANTS, check_mutants, mutate_scene
from mcrt.scene import Scene

__all__ = [
    "INTEGRATOR_MUTANTS",
    "SCENE_MUTANTS",
    "McrtIntegrator",
    "check_scene",
    "integrator_class",
    "parse_mutants",
    "register",
    "render_plugin",
]

#: Name under which the integrator is registered.
NAME = "mcrt"

#: Mutants of :mod:`mcrt.mutants` that the integrator implements (estimator bugs).
INTEGRATOR_MUTANTS = (
    "rr_no_divide",
    "nee_no_cos_light",
    "nee_no_cos_surface",
    "nee_no_inv_dist2",
    "nee_no_area",
    "double_count",
    "uniform_as_cosine",
    "ball_plus_normal",
    "brdf_no_inv_pi",
    "mirror_wrong_sign",
    "depth_off_by_one",
    "no_offset",
    "shadow_unbounded",
)
#: Mutants that change the scene, not the estimator: applied by :func:`render_plugin`.
SCENE_MUTANTS = ("albedo_1pct",)

UNBOUNDED = 2**32 - 1

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
    """Mutant names from a comma-separated string or an iterable, checked against the integrator's.

    Raises a one-line ``ValueError`` for an unknown name and for a mutant of
    the catalogue the integrator does not implement (camera, output and scene
    mutants: ``no_jitter``, ``gamma_output``, ``albedo_1pct`` (applied by
    :func:`render_plugin` instead), ``light_two_sided``).
    """
    if isinstance(spec, str):
        spec = [s.strip() for s in spec.split(",")]
    names = check_mutants(s for s in spec if s)
    other = sorted(names - set(INTEGRATOR_MUTANTS))
    if other:
        raise ValueError(
            f"mcrt integrator: mutant {other[0]!r} is not implemented inside Mitsuba "
            f"(it has: {', '.join(INTEGRATOR_MUTANTS)})"
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
# The integrator (one class per Mitsuba variant)
# --------------------------------------------------------------------------


def _define_class():
    """Define McrtIntegrator against the current variant's mi.SamplingIntegrator."""

    class McrtIntegrator(mi.SamplingIntegrator):
        r"""mcrt's estimator on Mitsuba's intersection, BSDFs and emitter sampling.

        For a camera ray it returns an unbiased sample of the radiance

        .. math::

            L(x, \omega_o) = L_e(x, \omega_o)
                + \int_{H^2} f(x, \omega_i, \omega_o) L(x', -\omega_i) |\cos\theta_i| \, d\omega_i

        truncated to paths of at most ``max_depth`` segments. At a diffuse
        (Lambertian) vertex the integral splits into

        * direct light from K emitter samples y_k (``scene.sample_emitter_direction``:
          an emitter chosen with probability p_sel, then for a mesh emitter a
          point uniform on its area, p_A = p_sel / A, as mcrt does; a sphere
          emitter samples its visible cone, another density with the same
          expectation):

          .. math::

              L_d = \frac{1}{K} \sum_k f(x, \omega_k, \omega_o) \, L_e(y_k, -\omega_k) \, V(x, y_k)
                    \frac{|\cos\theta_x| \, |\cos\theta_y|}{|x - y_k|^2 \, p_A(y_k)},

          which is ``bsdf.eval(...) * spec`` with Mitsuba's
          ``spec = L_e / p_{\omega}`` and p_omega = p_A d^2 / |cos theta_y|;

        * indirect light along one direction drawn by the BSDF (the cosine
          warp for ``diffuse``), with weight f |cos| / pdf = albedo; emission
          that ray finds is not counted (L_d has it).

        After a delta (mirror) bounce the weight is the reflectance and the
        emission found is counted, as it is from the sensor. From ``rr_depth``
        on, a path survives with probability q = min(max(beta), 0.95) and beta
        is divided by q.
        """

        def __init__(self, props):
            super().__init__(props)
            max_depth = int(props.get("max_depth", 8))
            if max_depth < -1:
                raise ValueError(f"mcrt integrator: max_depth must be -1 (unbounded) or >= 0, got {max_depth}")
            self.light_samples = int(props.get("light_samples", 1))
            if self.light_samples < 1:
                raise ValueError(f"mcrt integrator: light_samples must be >= 1, got {self.light_samples}")
            self.rr_depth = int(props.get("rr_depth", 5))
            if self.rr_depth < 1:
                raise ValueError(f"mcrt integrator: rr_depth must be >= 1, got {self.rr_depth}")
            self.mutants = parse_mutants(props.get("mutant", ""))
            self.max_depth_param = max_depth
            depth = UNBOUNDED if max_depth == -1 else max_depth
            if "depth_off_by_one" in self.mutants and depth != UNBOUNDED:
                depth += 1
            self.max_depth = depth
            self._checked: set[int] = set()

        def _check(self, scene):
            """check_scene (about 1 ms) at every trace: once per kernel in JIT variants.

            Scalar variants call sample() once per ray, so there the check runs
            once per scene object (by id).
            """
            if dr.is_jit_v(mi.Float):
                check_scene(scene)
            elif id(scene) not in self._checked:
                check_scene(scene)
                self._checked.add(id(scene))

        def to_string(self) -> str:
            mut = f", mutant='{','.join(sorted(self.mutants))}'" if self.mutants else ""
            return (
                f"McrtIntegrator[max_depth={self.max_depth_param}, light_samples={self.light_samples}, "
                f"rr_depth={self.rr_depth}, hide_emitters={self.hide_emitters}{mut}]"
            )

        def aov_names(self):
            return []

        # ------------------------------------------------------------------
        @dr.syntax
        def sample(self, scene, sampler, ray, medium=None, active=True):
            """One radiance sample per ray: (spectrum, valid, aovs)."""
            self._check(scene)

            # --------------------- Loop state ----------------------
            ray = mi.Ray3f(ray)                  # current ray
            L = mi.Spectrum(0.0)                 # radiance gathered so far
            beta = mi.Spectrum(1.0)              # path throughput: product of f cos / pdf so far
            depth = mi.UInt32(0)                 # path segments traced so far
            specular = mi.Bool(True)             # last vertex was the sensor or a mirror: count emission
            valid = mi.Bool(False)               # the camera ray hit something
            active = mi.Bool(active) & (self.max_depth > 0)

            while dr.hint(active, label="mcrt_path"):
                si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=depth == 0, active=active)
                depth += 1
                valid |= active & si.is_valid() & (depth == 1)

                # ---------------- Emission from the sensor or through mirrors ----------------
                counted = self._counts_emission(specular, depth)
                L += beta * si.emitter(scene).eval(si, active & counted)

                # ---------------- Stop at misses and at the depth limit ----------------
                active &= si.is_valid() & (depth < self.max_depth)
                bsdf = si.bsdf(ray)
                diffuse = active & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)

                # ---------------- Next-event estimation (depth + 1 <= max_depth here) ----------------
                L += beta * self.direct_light(scene, sampler, si, bsdf, diffuse)

                # ---------------- Continue: BSDF sample (cosine warp or mirror) ----------------
                wo, weight, specular = self.scatter(si, bsdf, sampler, diffuse, active)
                beta *= weight
                ray = self.spawn(si, wo)
                active &= dr.max(beta) > 0  # black surfaces (the light's) end the path

                # ---------------- Russian roulette ----------------
                beta, active = self.roulette(beta, depth, diffuse, active, sampler)

            return L, valid, []

        # ------------------------------------------------------------------
        def _counts_emission(self, specular, depth):
            """Count Le at this hit: after the sensor or a mirror (always, with double_count)."""
            counted = mi.Bool(True) if "double_count" in self.mutants else mi.Bool(specular)
            if self.hide_emitters:
                counted = counted & (depth > 1)
            return counted

        def spawn(self, si, d):
            """The ray leaving si along d, offset by Mitsuba's spawn_ray (not with no_offset)."""
            if "no_offset" in self.mutants:
                return mi.Ray3f(si.p, d)
            return si.spawn_ray(d)

        def scatter(self, si, bsdf, sampler, diffuse, active):
            """Next direction (world), weight f |cos| / pdf, and whether the bounce was a delta one."""
            ctx = mi.BSDFContext()
            bs, weight = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d(), active)
            wo_local = bs.wo
            mut = self.mutants
            if ("uniform_as_cosine" in mut) or ("ball_plus_normal" in mut):
                side = dr.select(mi.Frame3f.cos_theta(si.wi) < 0, -1.0, 1.0)  # wi's side (two-sided)
                if "ball_plus_normal" in mut:
                    u, v = sampler.next_2d(), sampler.next_1d()
                    b = mi.warp.square_to_uniform_sphere(u) * dr.cbrt(v)  # uniform in the unit ball
                    w = dr.normalize(b + mi.Vector3f(0.0, 0.0, 1.0))
                else:
                    w = mi.warp.square_to_uniform_hemisphere(sampler.next_2d())
                w = mi.Vector3f(w.x, w.y, w.z * side)
                # Weighted as if cosine-distributed: f |cos| / (|cos| / pi) = albedo.
                w_weight = bsdf.eval(ctx, si, w, diffuse) / mi.warp.square_to_cosine_hemisphere_pdf(mi.Vector3f(w.x, w.y, dr.abs(w.z)))
                wo_local = dr.select(diffuse, w, wo_local)
                weight = dr.select(diffuse, w_weight, weight)
            if "brdf_no_inv_pi" in mut:
                weight = dr.select(diffuse, weight * math.pi, weight)
            delta = active & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            wo = si.to_world(wo_local)
            if "mirror_wrong_sign" in mut:
                wo = dr.select(delta, -wo, wo)
            return wo, dr.select(active, weight, 0.0), delta

        def roulette(self, beta, depth, diffuse, active, sampler):
            """Unbiased Russian roulette: survive with q = min(max beta, 0.95), then beta /= q."""
            if "rr_no_divide" in self.mutants:
                survive = sampler.next_1d() >= 0.75
                return dr.select(diffuse, beta * 0.8, beta), active & (~diffuse | survive)
            q = dr.minimum(dr.max(beta), 0.95)
            roulette = active & (depth >= self.rr_depth)
            survive = sampler.next_1d() < q
            return dr.select(roulette, beta * dr.rcp(q), beta), active & (~roulette | survive)

        # ------------------------------------------------------------------
        def direct_light(self, scene, sampler, si, bsdf, active):
            """(1/K) sum_k f Le V |cos_x| |cos_y| / (d^2 p_A): K = 1 traces no loop."""
            if self.light_samples == 1:
                return self.light_sample(scene, sampler, si, bsdf, active)
            return self._light_sample_loop(scene, sampler, si, bsdf, active) * (1.0 / self.light_samples)

        @dr.syntax
        def _light_sample_loop(self, scene, sampler, si, bsdf, active):
            acc = mi.Spectrum(0.0)  # sum of the light samples so far
            k = mi.UInt32(0)        # light samples drawn
            while dr.hint(active & (k < self.light_samples), label="mcrt_light_samples"):
                acc += self.light_sample(scene, sampler, si, bsdf, active)
                k += 1
            return acc

        def light_sample(self, scene, sampler, si, bsdf, active):
            r"""One light sample: f(x, w, wo) |cos_x| Le(y, -w) V(x, y) |cos_y| / (d^2 p_A(y)).

            Mitsuba's ``spec = Le / p_omega`` already holds the area-to-solid-angle
            Jacobian, p_omega = p_A d^2 / |cos_y|; the mutants take factors out
            of the geometry term |cos_x| |cos_y| / d^2 or the 1/p_A.
            """
            mut = self.mutants
            ds, spec = scene.sample_emitter_direction(si, sampler.next_2d(), False, active)
            wo = si.to_local(ds.d)
            f = bsdf.eval(mi.BSDFContext(), si, wo, active)  # f |cos_x|; 0 unless wo is on wi's side
            if "brdf_no_inv_pi" in mut:
                f *= math.pi
            cos_y = dr.abs(dr.dot(ds.n, ds.d))
            d2 = dr.square(ds.dist)
            scale = mi.Float(1.0)
            if "nee_no_cos_surface" in mut:
                f /= dr.abs(mi.Frame3f.cos_theta(wo))
            if "nee_no_cos_light" in mut:
                scale /= cos_y
            if "nee_no_inv_dist2" in mut:
                scale *= d2
            if "nee_no_area" in mut:
                scale *= ds.pdf * cos_y / d2  # p_A: the light's pdf taken as 1 instead of 1/A
            contrib = f * spec * scale
            # Not `active &= ...`: Dr.Jit's in-place operators would change the caller's mask.
            active = active & (ds.pdf > 0) & dr.any(contrib != 0) & dr.all(dr.isfinite(contrib))

            # ---------------- Visibility: a shadow ray stopping short of y ----------------
            if "shadow_unbounded" in mut:
                shadow = si.spawn_ray(ds.d)
            elif "no_offset" in mut:
                shadow = mi.Ray3f(si.p, ds.d, ds.dist * (1.0 - mi.math.ShadowEpsilon))
            else:
                shadow = si.spawn_ray_to(ds.p)
            visible = ~scene.ray_test(shadow, active)
            return dr.select(active & visible, contrib, 0.0)

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


def render_plugin(
    scene: Scene,
    camera: str | None = None,
    width: int | None = None,
    height: int | None = None,
    spp: int | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    backend: str = "llvm",
    progress: bool = True,
    mutants=(),
    *,
    spp_per_pass: int | None = None,
) -> RenderResult:
    """Render ``scene`` with the ``mcrt`` integrator inside Mitsuba: mean and per-sample variance.

    The scene, sensor and passes are those of :func:`mcrt.mitsuba.render_mitsuba`
    (deterministic for a seed; None takes ``scene.render``'s value); only the
    integrator differs. ``mutants`` may hold :data:`INTEGRATOR_MUTANTS` and
    :data:`SCENE_MUTANTS`. The result has ``renderer='mitsuba-mcrt'``.
    """
    names = check_mutants(mutants)
    scene_mut = names & set(SCENE_MUTANTS)
    est_mut = parse_mutants(names - scene_mut)
    s = scene.settings(camera=camera, light_samples=light_samples)
    _use(backend)
    register()
    integrator = {"type": NAME, "light_samples": int(s.light_samples), "mutant": ",".join(sorted(est_mut))}
    r = render_mitsuba(
        mutate_scene(scene, scene_mut),
        camera=camera, width=width, height=height, spp=spp, seed=seed, max_depth=max_depth,
        backend=backend, progress=progress, spp_per_pass=spp_per_pass, integrator=integrator,
    )
    extra = dict(r.extra, light_samples=str(s.light_samples), mutants=",".join(sorted(names)))
    return dataclasses.replace(r, renderer="mitsuba-mcrt", scene_hash=scene.content_hash(), extra=extra)


assert set(INTEGRATOR_MUTANTS) | set(SCENE_MUTANTS) <= set(MUTANTS)
