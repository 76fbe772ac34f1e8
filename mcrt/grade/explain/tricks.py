"""Mistakes of a student's estimator that mcrt renders with a trick (:data:`mcrt.options.TRICK_OPTIONS`): each
variant's render minus the basis's, one seed for both, and the variant whose change fits best."""

from __future__ import annotations

import numpy as np

from mcrt.grade.explain.fit import Fit


def rendered_changes(a, scene, render, variants: list[tuple[object, dict]]) -> list[tuple[object, np.ndarray]]:
    """(key, render with the tricks minus the render without) for each (key, tricks) of ``variants``, at the basis's
    spp and seed (common random numbers)."""
    from mcrt.grade.explain.basis import basis_settings

    spp, seed = basis_settings(a)

    def img(**tricks):
        return render(scene, a.camera, a.grade_width, a.grade_height, a.max_depth, spp, seed,
                      **tricks).mean.astype(np.float64)

    base = img()
    return [(key, (img(**tricks) - base).astype(np.float32)) for key, tricks in variants]


def best_change(fit: Fit, changes: list[tuple[object, np.ndarray]]) -> tuple[float, object, np.ndarray] | None:
    """(chi^2, key, change) of the change of :func:`rendered_changes` that fits best, None without any."""
    if not changes:
        return None
    err, key, change = min(((fit.delta(c.astype(np.float64)), key, c) for key, c in changes), key=lambda t: t[0])
    return err, key, change.astype(np.float64)
