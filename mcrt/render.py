"""One renderer interface: every caller renders through :func:`render`.

Three renderers draw the same :class:`mcrt.scene.Scene` and return the same
:class:`mcrt.film.RenderResult` (mean and per-sample variance, reproducible
from the seed):

=========  ============================  ==================  ==============
name       what                          geometry            estimator
=========  ============================  ==================  ==============
mcrt       the standalone tracer         mcrt                mcrt
plugin     mcrt's estimator in Mitsuba   Mitsuba             mcrt
mitsuba    Mitsuba's ``path`` integrator Mitsuba             Mitsuba
=========  ============================  ==================  ==============

Each takes the options every renderer has (``backend``, ``progress``,
``spp_per_pass``) and its own, keyword-only; an option a renderer does not
have is refused with a one-line ``ValueError`` naming both. Every renderer
has the pixel sampler (``pixel_sampler``, ``replicates``: :mod:`mcrt.samplers`),
the same points and variance on each; adaptive sampling refuses ``sobol``::

    from mcrt.render import render
    s = scene.settings(camera="near", width=64, height=64, spp=256)
    a = render(scene, s, seed=1)                                  # renderer="mcrt"
    b = render(scene, s, renderer="mitsuba", seed=2)
    c = render(scene, s, renderer="plugin", seed=3, mutants=("nee_no_cos_light",))

Renderer ``mcrt`` is the standalone tracer (:func:`mcrt.tracer.render_tracer`)
at its defaults; its options ``bidirectional`` (:mod:`mcrt.bidir`),
``mirror_caustics`` (the path tracer's share of the paths eye D ... D S+ L),
``adaptive`` (:mod:`mcrt.tricks.adaptive`) and ``denoise``
(:mod:`mcrt.tricks.denoise`) render with those renderers instead
(:func:`render_mcrt`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from mcrt.film import RenderResult
from mcrt.scene import RenderSettings, Scene
from mcrt.options import TRICK_OPTIONS

#: Options that every renderer takes, with their defaults.
COMMON_OPTIONS = {"backend": "llvm", "progress": True, "spp_per_pass": None}

#: Tricks that work on whole renders, options of the ``mcrt`` renderer: ``adaptive`` one of
#: mcrt.tricks.adaptive.SCHEMES, ``denoise`` one of :data:`DENOISE_GUIDES`.
RENDER_TRICKS = {"adaptive": None, "denoise": None}
#: What guides the denoiser: the first-hit albedo and normal buffers, or the colour alone.
DENOISE_GUIDES = ("albedo+normal", "color")


@dataclass(frozen=True)
class Renderer:
    """A registered renderer: what it is, which options it takes, and the function that renders."""

    name: str
    description: str
    geometry: str  # whose intersection and scene representation: 'mcrt' or 'mitsuba'
    estimator: str  # whose path estimator: 'mcrt' or 'mitsuba'
    options: dict  # its own keyword-only options and their defaults
    load: Callable[[], Callable[..., RenderResult]]  # imports lazily: Mitsuba loads only when needed

    def __call__(self, scene: Scene, settings: RenderSettings, **options) -> RenderResult:
        known = {**COMMON_OPTIONS, **self.options}
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise ValueError(f"renderer {self.name!r} has no option {unknown[0]!r} (it has: {', '.join(sorted(known))})")
        return self.load()(scene, settings, **{**known, **options})


def render_mcrt(scene: Scene, settings: RenderSettings, *, adaptive: str | None = None, denoise: str | None = None,
                bidirectional: bool = False, mirror_caustics: str = "all", light_paths: float | str | None = None,
                **options) -> RenderResult:
    """Renderer ``mcrt``: the standalone tracer, or a bidirectional, caustic-split or adaptive render, then denoised where asked.

    At its defaults it is :func:`mcrt.tracer.render_tracer` itself.
    ``light_paths`` is the bidirectional estimator's budget (a number or
    'auto'; None: :func:`mcrt.bidir.render_bidirectional`'s default).
    """
    from mcrt.tracer import render_tracer

    if light_paths is not None and not bidirectional:
        raise ValueError("light_paths is the bidirectional estimator's budget: it needs bidirectional=True")

    if denoise is not None:
        if denoise not in DENOISE_GUIDES:
            raise ValueError(f"denoise must be one of {', '.join(DENOISE_GUIDES)}, got {denoise!r}")
        from mcrt.tricks.denoise import require_denoiser

        require_denoiser()  # before the render, not after it
    if adaptive is not None:
        result = _adaptive(scene, settings, adaptive, {**options, "bidirectional": bidirectional,
                                                      "mirror_caustics": mirror_caustics, "light_paths": light_paths})
    elif bidirectional:
        from mcrt.bidir import render_bidirectional

        budget = {} if light_paths is None else {"light_paths": light_paths}
        result = render_bidirectional(scene, settings, mirror_caustics=mirror_caustics, **budget, **options)
    elif mirror_caustics != "all":
        from mcrt.bidir import render_caustic_split

        result = render_caustic_split(scene, settings, mirror_caustics=mirror_caustics, **options)
    else:
        result = render_tracer(scene, settings, **options)
    if denoise is None:
        return result
    from mcrt.tricks.aov import first_hit_buffers
    from mcrt.tricks.denoise import denoise_result

    s = settings
    buffers = first_hit_buffers(scene, s.camera, s.width, s.height, backend=options.get("backend", "llvm")) \
        if denoise == "albedo+normal" else None
    return denoise_result(result, buffers)


#: The estimator's options an adaptive render keeps at their defaults (it renders with the default estimator).
ADAPTIVE_FIXED = {**TRICK_OPTIONS, "mutants": (), "intersector": "convex", "mis": None, "bidirectional": False,
                  "mirror_caustics": "all", "pixel_sampler": "independent", "replicates": None, "light_paths": None}


def _adaptive(scene: Scene, settings: RenderSettings, scheme: str, options: dict) -> RenderResult:
    from mcrt.tricks.adaptive import render_adaptive

    other = sorted(k for k, d in ADAPTIVE_FIXED.items() if k in options and options[k] != d and (d != () or options[k]))
    if "pixel_sampler" in other or "replicates" in other:
        raise ValueError("adaptive sampling takes no pixel_sampler 'sobol': it gives each pixel its own sample count "
                         "by the per-sample spread, and sobol's variance needs R equal replicates in every pixel")
    if other:
        raise ValueError(f"adaptive sampling renders with the default estimator: it takes no option {other[0]!r}")
    return render_adaptive(scene, settings, scheme=scheme, backend=options.get("backend", "llvm")).result


def _mcrt():
    return render_mcrt


def _mitsuba():
    from mcrt.mitsuba_scene import render_mitsuba

    return render_mitsuba


def _plugin():
    from mcrt.plugins import render_plugin

    return render_plugin


RENDERERS: dict[str, Renderer] = {
    r.name: r
    for r in (
        Renderer("mcrt", "the standalone Dr.Jit tracer", "mcrt", "mcrt",
                 {"mutants": (), "intersector": "convex", "mis": None, "precision_guard": True, **TRICK_OPTIONS,
                  "bidirectional": False, "mirror_caustics": "all", **RENDER_TRICKS,
                  "pixel_sampler": "independent", "replicates": None, "light_paths": None}, _mcrt),
        Renderer("plugin", "mcrt's estimator as the Mitsuba integrator 'mcrt'", "mitsuba", "mcrt",
                 {"mutants": (), "mis": None, "pixel_sampler": "independent", "replicates": None}, _plugin),
        Renderer("mitsuba", "Mitsuba 3's path integrator", "mitsuba", "mitsuba",
                 {"integrator": "path", "pixel_sampler": "independent", "replicates": None}, _mitsuba),
    )
}


def get_renderer(name: str) -> Renderer:
    """The registered renderer ``name``; a one-line ``ValueError`` names the known ones otherwise."""
    try:
        return RENDERERS[name]
    except KeyError:
        raise ValueError(f"unknown renderer {name!r} (one of {', '.join(RENDERERS)})") from None


def render(scene: Scene, settings: RenderSettings | None = None, *, renderer: str = "mcrt", seed: int | None = None,
           **options) -> RenderResult:
    """Render ``scene`` at ``settings`` (default: the scene file's) with one registered renderer.

    ``seed`` (default ``settings.seed``) makes the render reproducible bit for
    bit; different seeds give independent images. ``options`` are the
    renderer's keyword-only options (:data:`RENDERERS`).
    """
    s = scene.settings() if settings is None else settings
    if seed is not None:
        s = replace(s, seed=int(seed))
    return get_renderer(renderer)(scene, s, **options)
