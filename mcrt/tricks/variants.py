"""The renders the tricks report compares: plain mcrt and each trick's variants, rendered one way.

A :class:`Variant` is one configuration of one trick: the renderer options
it passes to :func:`mcrt.render.render` (the estimator's tricks of
the ``mcrt`` renderer's :data:`mcrt.options.TRICK_OPTIONS`), or a render that wraps the tracer (adaptive
sampling, denoising). ``claim`` is what theory says of its expectation
('unbiased' or 'biased'); the report sets it beside what the statistical
comparison finds.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from mcrt.film import RenderResult
from mcrt.scene import RenderSettings, Scene

#: The tricks in the order the report shows them (the lecture's order), and the baseline.
TRICKS = ("roulette", "adaptive", "bidirectional", "denoise", "light")
PLAIN = "mcrt"


@dataclass(frozen=True)
class Variant:
    """One configuration of one trick (or plain mcrt)."""

    label: str
    trick: str  # one of TRICKS, or 'plain'
    claim: str  # 'unbiased' or 'biased': what theory says of its expectation
    options: dict = field(default_factory=dict)  # renderer options of mcrt.render.render
    light_samples: int | None = None  # K, where the variant changes it
    adaptive: str | None = None  # mcrt.tricks.adaptive.SCHEMES
    denoise: str | None = None  # 'albedo+normal' or 'color': the denoiser's guides

    def render(self, scene: Scene, settings: RenderSettings, seed: int, *, buffers=None,
               backend: str = "llvm") -> tuple[RenderResult, object]:
        """The variant's render of ``settings`` at ``seed`` (its wall time: all the trick costs but the buffers).

        Returns the render and, for adaptive sampling, the
        :class:`mcrt.tricks.adaptive.AdaptiveRender` with its per-pixel
        sample counts (None otherwise).
        """
        from mcrt.render import render

        s = settings if self.light_samples is None else replace(settings, light_samples=self.light_samples)
        s = replace(s, seed=int(seed))
        if self.adaptive is not None:
            from mcrt.tricks.adaptive import render_adaptive

            a = render_adaptive(scene, s, scheme=self.adaptive, backend=backend)
            return a.result, a
        result = render(scene, s, progress=False, backend=backend, **self.options)
        if self.denoise is not None:
            from mcrt.tricks.denoise import denoise_result

            result = denoise_result(result, buffers if self.denoise == "albedo+normal" else None)
        return result, None


def _roulette() -> list[Variant]:
    return [
        Variant("throughput q from depth 1", "roulette", "unbiased", {"roulette_start": 1}),
        Variant("throughput q from depth 3", "roulette", "unbiased", {"roulette_start": 3}),
        Variant("fixed q = 0.5 from depth 1", "roulette", "unbiased", {"roulette_survival": 0.5, "roulette_start": 1}),
        Variant("fixed q = 0.25 from depth 1", "roulette", "unbiased", {"roulette_survival": 0.25, "roulette_start": 1}),
        Variant("no roulette", "roulette", "unbiased", {"roulette_start": 10**6}),
        Variant("course2023 from depth 1", "roulette", "biased", {"roulette": "course2023"}),
        Variant("course2023 from depth 3", "roulette", "biased", {"roulette": "course2023", "roulette_start": 3}),
        Variant("course2023 from depth 5", "roulette", "biased", {"roulette": "course2023", "roulette_start": 5}),
    ]


def default_variants(*, bidirectional: bool = True) -> list[Variant]:
    """Plain mcrt, then every trick's variants; the bidirectional estimator where the renderer has it."""
    out = [Variant(PLAIN, "plain", "unbiased")]
    out += _roulette()
    out += [
        Variant("adaptive naive (same samples)", "adaptive", "biased", adaptive="naive"),
        Variant("adaptive two-stage (fresh samples)", "adaptive", "unbiased", adaptive="two-stage"),
    ]
    if bidirectional and has_bidirectional():
        out.append(Variant("bidirectional", "bidirectional", "unbiased", {"bidirectional": True}))
    out += [
        Variant("OIDN, albedo + normal", "denoise", "biased", denoise="albedo+normal"),
        Variant("OIDN, colour only", "denoise", "biased", denoise="color"),
        Variant("solid angle (spherical rectangle)", "light", "unbiased", {"light_sampling": "solid_angle"}),
        Variant("K = 4 shadow rays", "light", "unbiased", light_samples=4),
    ]
    return out


def has_bidirectional() -> bool:
    """Whether the ``mcrt`` renderer takes ``bidirectional=True`` (the bidirectional estimator)."""
    from mcrt.render import RENDERERS

    return "bidirectional" in RENDERERS["mcrt"].options
