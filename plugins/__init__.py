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

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import mitsuba as mi

from mcrt.film import RenderResult
from mcrt.light import needs_mis
from mcrt.mitsuba_scene import _use, render_mitsuba
from mcrt.mutants import CATALOGUE, camera_jitter, check_mutants, mutate_scene, output_encoding
from mcrt.plugins.host import MitsubaHost
from mcrt.plugins.integrator import NAME, _on_variant_change, integrator_class, parse_mutants, register
from mcrt.plugins.scene_check import check_scene
from mcrt.scene import RenderSettings, Scene
from mcrt.srgb import encode_output

__all__ = ["MitsubaHost", "McrtIntegrator", "check_scene", "integrator_class", "parse_mutants", "register", "render_plugin"]


def __getattr__(name: str):
    # mcrt.plugins.McrtIntegrator: the class of the current variant.
    if name == "McrtIntegrator":
        return integrator_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


mi.detail.add_variant_callback(_on_variant_change)
if mi.variant() is not None:
    register()


def render_plugin(scene: Scene, settings: RenderSettings, *, backend: str = "llvm", progress: bool = True,
                  spp_per_pass: int | None = None, mutants=(), mis: bool | None = None,
                  pixel_sampler: str = "independent", replicates: int | None = None) -> RenderResult:
    """Render ``scene`` at ``settings`` with the ``mcrt`` integrator inside Mitsuba: mean and per-sample variance.

    Called through :func:`mcrt.render.render` (renderer ``plugin``). The
    scene, sensor and passes are those of :func:`mcrt.mitsuba_scene.render_mitsuba`;
    only the integrator differs. Every catalogued mutant runs: the
    estimator's inside the integrator, the camera's (jitter) in the passes,
    the output's on the image and the scene's on the scene. ``mis`` as in the
    standalone tracer (default: where the scene needs it). ``pixel_sampler``
    and ``replicates`` as in the standalone tracer (:mod:`mcrt.samplers`):
    ``sobol`` places the camera samples at the tracer's Owen-scrambled Sobol
    points in R replicates, the variance is the replicates' spread and the
    header says ``variance_method`` 'replicates:R' (R - 1 df). The result
    has ``renderer='mitsuba-mcrt'``.
    """
    names = check_mutants(mutants)
    mutated = mutate_scene(scene, names)
    use_mis = needs_mis(mutated) if mis is None else bool(mis)
    _use(backend)
    register()
    integrator = {"type": NAME, "light_samples": int(settings.light_samples), "mis": use_mis,
                  "mutant": ",".join(sorted(n for n in names if CATALOGUE[n].mutations))}
    r = render_mitsuba(mutated, settings, backend=backend, progress=progress, spp_per_pass=spp_per_pass,
                       integrator=integrator, jitter=camera_jitter(names), pixel_sampler=pixel_sampler,
                       replicates=replicates)
    mean, var = encode_output(r.mean, r.variance, output_encoding(names))
    extra = dict(r.extra, light_samples=str(settings.light_samples), mis=str(use_mis).lower(), mutants=",".join(sorted(names)))
    return dataclasses.replace(r, mean=mean, variance=var, renderer="mitsuba-mcrt", scene_hash=scene.content_hash(), extra=extra)
