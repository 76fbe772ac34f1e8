"""Numbers as the feedback and reports print them."""

from __future__ import annotations


def short(x: float) -> str:
    """At most two decimals, trailing zeros dropped: 2.5, 3, 0.25 (points, scores, factors)."""
    return f"{x:.2f}".rstrip("0").rstrip(".")
