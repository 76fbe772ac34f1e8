"""Multiple testing: Holm, Bonferroni and Benjamini-Hochberg adjusted p-values."""

from __future__ import annotations

import numpy as np

__all__ = ["CORRECTIONS", "adjust_p_values", "reject"]

#: Procedure name -> (error rate it bounds, display name).
CORRECTIONS = {
    "holm": ("FWER", "Holm"),
    "bonferroni": ("FWER", "Bonferroni"),
    "bh": ("FDR", "Benjamini-Hochberg"),
}


def check_correction(method: str) -> None:
    """Raise ``ValueError`` unless ``method`` is a key of :data:`CORRECTIONS`."""
    if method not in CORRECTIONS:
        raise ValueError(f"correction must be one of {sorted(CORRECTIONS)}, got {method!r}")


def adjust_p_values(p_values, method: str = "holm") -> np.ndarray:
    """Multiplicity-adjusted p-values, same shape as the input.

    A test is rejected at level alpha exactly when its adjusted p-value is
    <= alpha. With the m p-values sorted ascending, p_(1) <= ... <= p_(m):

    * Bonferroni: ``p~_i = min(1, m p_i)`` (family-wise error rate).
    * Holm (step-down): ``p~_(i) = max_{j <= i} min(1, (m - j + 1) p_(j))``,
      which rejects H_(1..k) for the largest k with
      ``p_(j) <= alpha / (m - j + 1)`` for all j <= k. Controls the
      family-wise error rate under any dependence, and is never less powerful
      than Bonferroni.
    * Benjamini-Hochberg (``'bh'``, step-up):
      ``p~_(i) = min_{j >= i} min(1, m p_(j) / j)``, which rejects H_(1..k)
      for the largest k with ``p_(k) <= k alpha / m``. Controls the false
      discovery rate for independent (or positively dependent) tests.

    Parameters
    ----------
    p_values : array_like
        Raw p-values in [0, 1], any shape.
    method : {'holm', 'bonferroni', 'bh'}

    Returns
    -------
    numpy.ndarray
        Adjusted p-values (float64), same shape as ``p_values``.
    """
    check_correction(method)
    p = np.asarray(p_values, dtype=np.float64)
    flat = p.ravel()
    m = flat.size
    if m == 0:
        return p.copy()
    if method == "bonferroni":
        return np.minimum(1.0, m * p)
    order = np.argsort(flat, kind="stable")
    ps = flat[order]
    rank = np.arange(1, m + 1, dtype=np.float64)
    if method == "holm":
        adj = np.maximum.accumulate(np.minimum(1.0, (m - rank + 1) * ps))
    else:  # bh
        adj = np.minimum.accumulate((m * ps / rank)[::-1])[::-1]
        adj = np.minimum(1.0, adj)
    out = np.empty(m)
    out[order] = adj
    return out.reshape(p.shape)


def reject(p_values, alpha: float, method: str = "holm") -> np.ndarray:
    """Boolean mask of the tests rejected at level ``alpha`` by ``method``:
    ``adjust_p_values(p_values, method) <= alpha`` (see :func:`adjust_p_values`)."""
    return adjust_p_values(p_values, method) <= alpha
