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
have is refused with a one-line ``ValueError`` naming both::

    from mcrt.render import render
    s = scene.settings(camera="near", width=64, height=64, spp=256)
    a = render(scene, s, seed=1)                                  # renderer="mcrt"
    b = render(scene, s, renderer="mitsuba", seed=2)
    c = render(scene, s, renderer="plugin", seed=3, mutants=("nee_no_cos_light",))
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from mcrt.film import RenderResult
from mcrt.scene import RenderSettings, Scene
from mcrt.tricks.options import RENDER_TRICKS, TRICK_OPTIONS

#: Options that every renderer takes, with their defaults.
COMMON_OPTIONS = {"backend": "llvm", "progress": True, "spp_per_pass": None}


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


def _tracer():
    from mcrt.tricks.render import render_mcrt  # render_tracer, with adaptive sampling and denoising as options

    return render_mcrt


def _mitsuba():
    from mcrt.mitsuba import render_mitsuba

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
                  "pixel_sampler": "independent", "replicates": None, "light_paths": None}, _tracer),
        Renderer("plugin", "mcrt's estimator as the Mitsuba integrator 'mcrt'", "mitsuba", "mcrt",
                 {"mutants": (), "mis": None}, _plugin),
        Renderer("mitsuba", "Mitsuba 3's path integrator", "mitsuba", "mitsuba", {"integrator": "path"}, _mitsuba),
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
