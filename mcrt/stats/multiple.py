"""Multiple testing: Holm, Bonferroni and Benjamini-Hochberg adjusted p-values."""

from __future__ import annotations

import numpy as np

__all__ = ["CORRECTIONS", "adjust_p_values", "adjust_p_values_weighted", "reject"]

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


def adjust_p_values_weighted(p_values, weights) -> np.ndarray:
    r"""Weighted Holm adjusted p-values (Holm 1979): one family-wise error rate over tests of unequal weight.

    With the tests sorted by :math:`p_i / w_i` ascending, test (j) is
    rejected at level alpha when :math:`p_{(i)} \le \alpha\, w_{(i)} / \sum_{k \ge i} w_{(k)}`
    for every i <= j; the adjusted p-value is
    :math:`\tilde p_{(j)} = \max_{i \le j} \min(1, p_{(i)} \sum_{k \ge i} w_{(k)} / w_{(i)})`.
    Equal weights give :func:`adjust_p_values` with ``'holm'``. The weights
    split the error rate between groups of tests (a group's weights summing
    to its share) without a Bonferroni split's loss within each group.
    """
    p = np.asarray(p_values, dtype=np.float64).ravel()
    w = np.broadcast_to(np.asarray(weights, dtype=np.float64), p.shape).ravel()
    if p.size == 0:
        return p.copy()
    if np.any(w <= 0):
        raise ValueError("weights must be positive")
    order = np.argsort(p / w, kind="stable")
    ws = w[order]
    tail = np.cumsum(ws[::-1])[::-1]  # sum of the weights from rank i on
    adj = np.maximum.accumulate(np.minimum(1.0, p[order] * tail / ws))
    out = np.empty(p.size)
    out[order] = adj
    return out.reshape(np.shape(p_values))
