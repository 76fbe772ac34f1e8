"""Three-way comparison: where does a disagreement come from?

The same scene is rendered by

- ``mcrt``: the standalone tracer (its own geometry, sampling and estimator),
- ``plugin``: mcrt's estimator inside Mitsuba (Mitsuba's geometry and sampling),
- ``mitsuba``: Mitsuba's path integrator (Mitsuba's geometry and estimator).

mcrt and the plugin share the estimator, the plugin and Mitsuba share the
geometry. So if mcrt differs from the plugin while the plugin agrees with
Mitsuba, the standalone tracer's geometry, intersection or sampling is at
fault; if the plugin differs from Mitsuba while mcrt agrees with the plugin,
the estimator is.
"""

from __future__ import annotations

from dataclasses import dataclass

from mcrt.stats import Comparison, compare_images


@dataclass
class ThreeWay:
    mcrt_vs_plugin: Comparison
    plugin_vs_mitsuba: Comparison
    mcrt_vs_mitsuba: Comparison

    @property
    def verdict(self) -> str:
        a, b = self.mcrt_vs_plugin.passed, self.plugin_vs_mitsuba.passed
        if a and b and self.mcrt_vs_mitsuba.passed:
            return "consistent: all three renders agree"
        if not a and b:
            return "geometry: mcrt differs from its own estimator inside Mitsuba, which agrees with Mitsuba's path integrator; look at mcrt's intersection, camera or sampling code"
        if a and not b:
            return "estimator: mcrt agrees with its estimator inside Mitsuba, which differs from Mitsuba's path integrator; look at the estimator (the plugin and mcrt share it)"
        if not a and not b:
            return "both: mcrt differs from the plugin and the plugin from Mitsuba; the geometry and the estimator may both be wrong"
        return "inconclusive: the pairwise tests disagree with each other (a borderline case; render more samples)"

    def summary(self) -> str:
        lines = [self.verdict]
        for name, c in (("mcrt vs plugin", self.mcrt_vs_plugin), ("plugin vs mitsuba", self.plugin_vs_mitsuba), ("mcrt vs mitsuba", self.mcrt_vs_mitsuba)):
            lines.append(f"  {name:18s} {c.summary()}")
        return "\n".join(lines)


def three_way(scene, settings, *, mutants=(), backend="llvm", alpha=0.01, tile=8, progress=True) -> ThreeWay:
    """Render with the three renderers at ``settings`` (seeds seed, seed+1, seed+2) and compare pairwise.

    ``mutants`` apply to both renderings of mcrt's estimator (standalone and plugin).
    """
    from mcrt.render import render

    a = render(scene, settings, seed=settings.seed, backend=backend, progress=progress, mutants=mutants)
    p = render(scene, settings, renderer="plugin", seed=settings.seed + 1, backend=backend, progress=progress, mutants=mutants)
    m = render(scene, settings, renderer="mitsuba", seed=settings.seed + 2, backend=backend, progress=progress)
    return ThreeWay(compare_images(a, p, alpha=alpha, tile=tile), compare_images(p, m, alpha=alpha, tile=tile),
                    compare_images(a, m, alpha=alpha, tile=tile))


def register(sub) -> None:
    p = sub.add_parser("threeway", help="render with mcrt, the plugin and Mitsuba; say whether a disagreement is geometry or estimator")
    p.add_argument("--scene", default=None, help="scene file (default: the canonical room shipped with mcrt, canonical.toml)")
    p.add_argument("--camera", default=None, help="camera name (default: the scene file's)")
    p.add_argument("--res", type=int, default=64, help="square resolution (default: 64)")
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel of each render (default: 1024)")
    p.add_argument("--seed", type=int, default=1, help="seed of mcrt's render; the plugin's is seed + 1, Mitsuba's seed + 2 (default: 1)")
    p.add_argument("--max-depth", type=int, default=None, help="longest path in segments, -1 unbounded (default: the scene file's)")
    p.add_argument("--light-samples", type=int, default=None, help="shadow rays per diffuse vertex (default: the scene file's)")
    p.add_argument("--mutant", action="append", metavar="NAME",
                   help="a catalogued bug in mcrt's estimator, on both of its hosts (repeatable; default: none)")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate of each comparison (default: 0.01)")
    p.add_argument("--tile", type=int, default=8, help="tile size in pixels (default: 8)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm", help="Dr.Jit backend (default: llvm)")
    p.set_defaults(func=cmd_threeway)


def cmd_threeway(args) -> int:
    from mcrt.scene import CANONICAL, load_scene

    scene = load_scene(args.scene or CANONICAL)
    s = scene.settings(camera=args.camera, width=args.res, height=args.res, spp=args.spp, seed=args.seed,
                       max_depth=args.max_depth, light_samples=args.light_samples)
    result = three_way(scene, s, mutants=args.mutant or (), backend=args.backend, alpha=args.alpha, tile=args.tile)
    print(result.summary())
    return 0 if result.verdict.startswith("consistent") else 1
