"""The ``mcrt`` renderer with the whole-render tricks: adaptive sampling and denoising as render options.

:func:`render_mcrt` is what :func:`mcrt.render.render` calls for renderer
``mcrt``: at ``adaptive=None, denoise=None`` (the defaults) it is
:func:`mcrt.tracer.render_tracer` itself, so the default image is unchanged.
"""

from __future__ import annotations

from mcrt.film import RenderResult
from mcrt.scene import RenderSettings, Scene
from mcrt.tricks.options import DENOISE_GUIDES, TRICK_OPTIONS


def render_mcrt(scene: Scene, settings: RenderSettings, *, adaptive: str | None = None, denoise: str | None = None,
                **options) -> RenderResult:
    """render_tracer, or a bidirectional (``bidirectional``) or adaptive render (``adaptive``), then denoised (``denoise``) where asked."""
    from mcrt.tracer import render_tracer

    if denoise is not None:
        if denoise not in DENOISE_GUIDES:
            raise ValueError(f"denoise must be one of {', '.join(DENOISE_GUIDES)}, got {denoise!r}")
        from mcrt.tricks.denoise import require_denoiser

        require_denoiser()  # before the render, not after it
    bidirectional = options.pop("bidirectional", False)
    light_paths = options.pop("light_paths", None)  # the bidirectional estimator's budget (a number or 'auto')
    if light_paths is not None and not bidirectional:
        raise ValueError("light_paths is the bidirectional estimator's budget: it needs bidirectional=True")
    if light_paths is not None:
        options["light_paths"] = light_paths
    if adaptive is None and bidirectional:
        from mcrt.bidir import render_bidirectional

        result = render_bidirectional(scene, settings, **options)
    elif adaptive is None:
        result = render_tracer(scene, settings, **options)
    else:
        result = _adaptive(scene, settings, adaptive, {**options, "bidirectional": bidirectional})
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
                  "mirror_caustics": "all", "pixel_sampler": "independent", "replicates": None,
                 "light_paths": None}


def _adaptive(scene: Scene, settings: RenderSettings, scheme: str, options: dict) -> RenderResult:
    from mcrt.tricks.adaptive import render_adaptive

    other = sorted(k for k, d in ADAPTIVE_FIXED.items() if k in options and options[k] != d and (d != () or options[k]))
    if other:
        raise ValueError(f"adaptive sampling renders with the default estimator: it takes no option {other[0]!r}")
    return render_adaptive(scene, settings, scheme=scheme, backend=options.get("backend", "llvm")).result
