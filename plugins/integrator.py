"""The Mitsuba integrator ``mcrt``: mcrt's estimator on :class:`mcrt.plugins.host.MitsubaHost`, and its registration.

Mitsuba's classes exist only once a variant is chosen, so the class is
defined per variant on first use, and :func:`register` runs on import when a
variant is set and again on every later ``mi.set_variant`` (a variant
callback).
"""

from __future__ import annotations

import mcrt  # noqa: F401  (sets DRJIT_LIBLLVM_PATH before drjit is imported)
import mitsuba as mi

from mcrt.estimator import PathEstimator
from mcrt.options import EstimatorOptions
from mcrt.mutants import CATALOGUE, check_mutants, mutation_values
from mcrt.plugins.host import MitsubaHost
from mcrt.plugins.scene_check import check_scene

#: Name under which the integrator is registered.
NAME = "mcrt"


def parse_mutants(spec) -> frozenset[str]:
    """Mutant names from a comma-separated string or an iterable: the estimator's bugs only.

    Raises a one-line ``ValueError`` for an unknown name and for a bug of the
    camera, the output or the scene, which the integrator cannot apply
    (:func:`render_plugin` does).
    """
    if isinstance(spec, str):
        spec = [s.strip() for s in spec.split(",")]
    names = check_mutants(s for s in spec if s)
    other = sorted(n for n in names if not CATALOGUE[n].mutations)
    if other:
        raise ValueError(
            f"mcrt integrator: mutant {other[0]!r} changes the camera, the output or the scene, not the estimator: "
            f"render with mcrt.render.render(..., renderer='plugin', mutants=...) instead"
        )
    return names


def _define_class():
    """Define McrtIntegrator against the current variant's mi.SamplingIntegrator."""

    class McrtIntegrator(mi.SamplingIntegrator):
        """mcrt's estimator (:class:`mcrt.estimator.PathEstimator`) on :class:`MitsubaHost`."""

        def __init__(self, props):
            super().__init__(props)
            try:
                self.mutants = parse_mutants(props.get("mutant", ""))
                self.options = EstimatorOptions.build(
                    max_depth=int(props.get("max_depth", 8)), light_samples=int(props.get("light_samples", 1)),
                    rr_depth=int(props.get("rr_depth", 5)), mis=bool(props.get("mis", False)),
                    hide_emitters=self.hide_emitters, **mutation_values(self.mutants),
                )
            except ValueError as e:
                raise ValueError(str(e) if str(e).startswith("mcrt integrator:") else f"mcrt integrator: {e}") from None

        def to_string(self) -> str:
            o = self.options.settings
            mut = f", mutant='{','.join(sorted(self.mutants))}'" if self.mutants else ""
            return (f"McrtIntegrator[max_depth={o.max_depth}, light_samples={o.light_samples}, rr_depth={o.rr_depth}, "
                    f"mis={o.mis}, hide_emitters={o.hide_emitters}{mut}]")

        def aov_names(self):
            return []

        def sample(self, scene, sampler, ray, medium=None, active=True):
            """One radiance sample per ray: (spectrum, valid, aovs)."""
            check_scene(scene)  # once per traced kernel, not per sample
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
