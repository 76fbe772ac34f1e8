r"""Each pixel's samples combined by another statistic than their mean: a median, a trimmed mean.

A program that fights fireflies by taking each pixel's median, or its mean
with the lowest and highest few per cent dropped (``scipy.stats.trim_mean``),
keeps the estimator's paths and loses the rare bright samples that carry
much of the indirect light: surfaces lit mostly indirectly darken, the light
and what it lights directly hardly change. The bias depends on how the
samples are distributed, which only rendering tells: mcrt renders the scene
with each statistic of :data:`mcrt.options.PIXEL_STATISTICS` (its trick
``pixel_statistic``: the same paths, one sample at a time) at the basis's
seed, with the assignment's spp and :data:`COUNTS` samples a pixel. No free
parameter.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_settings
from mcrt.options import PIXEL_STATISTICS
from mcrt.scene import Scene

#: What each statistic is, in a student's terms.
WORDS = {"median": "the median of its samples",
         "trimmed_5": "the mean of its samples with the lowest and the highest 5 % dropped (a trimmed mean)",
         "trimmed_10": "the mean of its samples with the lowest and the highest 10 % dropped (a trimmed mean)"}


#: Samples a pixel rendered for each statistic besides the assignment's spp: a median's or a trimmed mean's bias
#: changes with how many samples it takes (the grade pixel of a larger image averages pixels of the declared spp).
COUNTS = (256, 1024)


def _prepare(a, scene: Scene, render) -> dict:
    """{(statistic, samples a pixel): mcrt's render with it} at the basis's seed (the module docstring)."""
    _, seed = basis_settings(a)
    return {(how, n): render(scene, a.camera, a.grade_width, a.grade_height, a.max_depth, n, seed,
                             pixel_statistic=how).mean.astype(np.float32)
            for how in PIXEL_STATISTICS if how != "mean" for n in sorted({a.spp, *COUNTS})}


def pixel_statistic(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each statistic of :data:`WORDS`, rendered (the module docstring)."""
    r = inputs.basis.extra.get(pixel_statistic.name)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    out = []
    for (how, n), im in r.items():
        change = im.astype(np.float64) - base
        text = (f"each pixel {WORDS[how]}, not their mean (fireflies fought by a statistic: the rare bright samples "
                f"that carry the indirect light lost; as rendered with {n} samples a pixel)")
        out.append(Candidate("pixel_statistic", f"{how.replace('_', ' ')} of {n}", text, fit.delta(change), 0,
                             value={"statistic": how, "samples": n}, change=change))
    return out


pixel_statistic.name, pixel_statistic.prepare = "pixel_statistic", _prepare
