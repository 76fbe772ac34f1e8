"""Numbers as the feedback and reports print them."""

from __future__ import annotations


def short(x: float) -> str:
    """At most two decimals, trailing zeros dropped: 2.5, 3, 0.25 (points, scores, factors); a value that two
    decimals would round to 0 keeps two significant digits: 0.0031, never 0."""
    if x != 0 and abs(x) < 0.005:
        return f"{x:.2g}"
    return f"{x:.2f}".rstrip("0").rstrip(".")
