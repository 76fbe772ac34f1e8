"""The efficiency tricks as options of the ``mcrt`` renderer, each off at its default.

:func:`mcrt.render.render` (renderer ``mcrt``) and ``mcrt render`` take them;
at their defaults the estimator is the one it has always been, bit for bit.

==================  ============  =============================================================
option              default       what it does (:class:`mcrt.estimator.EstimatorOptions`)
==================  ============  =============================================================
roulette            'unbiased'    'course2023': the 2023 course's absorb-0.75, times-0.8 (biased)
roulette_survival   None          a fixed survival probability instead of the scheme's own
roulette_start      None          the first depth roulette runs at instead of the scheme's own
light_sampling      'area'        'solid_angle': the light sampled as a spherical rectangle
==================  ============  =============================================================

Adaptive sampling (``adaptive='naive'`` or ``'two-stage'``,
:mod:`mcrt.tricks.adaptive`) and denoising (``denoise='albedo+normal'`` or
``'color'``, :mod:`mcrt.tricks.denoise`) work on whole renders: options of
the renderer too, handled by :func:`mcrt.tricks.render.render_mcrt`.
"""

from __future__ import annotations

#: Name -> default of every estimator trick the ``mcrt`` renderer takes.
TRICK_OPTIONS = {"roulette": "unbiased", "roulette_survival": None, "roulette_start": None, "light_sampling": "area"}


def trick_options(tricks: dict) -> tuple:
    """The tricks that differ from their defaults, as sorted (name, value) pairs (hashable, for a tracer's cache)."""
    unknown = sorted(set(tricks) - set(TRICK_OPTIONS))
    if unknown:
        raise ValueError(f"no trick option {unknown[0]!r} (have: {', '.join(TRICK_OPTIONS)})")
    return tuple(sorted((k, v) for k, v in tricks.items() if v != TRICK_OPTIONS[k]))


#: Tricks that work on whole renders, options of the ``mcrt`` renderer too (:func:`mcrt.tricks.render.render_mcrt`):
#: ``adaptive`` one of mcrt.tricks.adaptive.SCHEMES, ``denoise`` one of :data:`DENOISE_GUIDES`.
RENDER_TRICKS = {"adaptive": None, "denoise": None}
#: What guides the denoiser: the first-hit albedo and normal buffers, or the colour alone.
DENOISE_GUIDES = ("albedo+normal", "color")
