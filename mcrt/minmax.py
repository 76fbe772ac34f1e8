"""Minimum, maximum and clamps for the path kernel, written as compare-and-select.

Dr.Jit lowers ``dr.minimum``, ``dr.maximum`` and ``dr.clip`` on floats to
LLVM's ``llvm.minimum`` / ``llvm.maximum`` (IEEE 754-2019: NaN-propagating,
-0 below +0). LLVM's x86 back end (seen with libLLVM 23) sometimes
scalarises one lane of such an operation inside a large kernel and then
fails to select the scalar instruction ("LLVM ERROR: Cannot select: f32 =
fminimum"), aborting the process; which kernels it hits changes with
unrelated edits elsewhere in the loop. A compare and a select compiles to
the same vector instructions and never takes that path. For the
non-NaN inputs the kernel sees, the results equal dr.minimum's and
dr.maximum's up to the sign of a zero.
"""

from __future__ import annotations

import drjit as dr


def fmin(a, b):
    """The smaller of a and b (b where they are equal)."""
    return dr.select(a < b, a, b)


def fmax(a, b):
    """The larger of a and b (b where they are equal)."""
    return dr.select(a > b, a, b)


def clamp(x, lo, hi):
    """x limited to [lo, hi] (lo <= hi)."""
    return fmin(fmax(x, lo), hi)


def sqrt0(x):
    """sqrt(max(x, 0)): the root of a quantity that rounding may push just below zero."""
    return dr.sqrt(fmax(x, 0.0))
