"""Mistakes of a student's estimator that mcrt renders with a trick (:data:`mcrt.options.TRICK_OPTIONS`): each
variant's render minus the basis's, one seed for both, and the variant whose change fits best."""

from __future__ import annotations

import numpy as np

from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_renderer


def rendered_changes(a, scene, render, variants: list[tuple[object, dict]]) -> list[tuple[object, np.ndarray]]:
    """(key, render with the tricks minus the render without) for each (key, tricks) of ``variants``, at the basis's
    spp and seed (common random numbers)."""
    img = basis_renderer(a, render)
    base = img(scene)
    return [(key, img(scene, **tricks) - base) for key, tricks in variants]


def best_change(fit: Fit, changes: list[tuple[object, np.ndarray]]) -> tuple[float, object, np.ndarray] | None:
    """(chi^2, key, change) of the change of :func:`rendered_changes` that fits best, None without any."""
    if not changes:
        return None
    err, key, change = min(((fit.delta(c.astype(np.float64)), key, c) for key, c in changes), key=lambda t: t[0])
    return err, key, change.astype(np.float64)
