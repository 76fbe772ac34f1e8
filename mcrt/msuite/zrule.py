r"""Mitsuba's own render test, applied to a render mcrt made at the same budget.

Mitsuba 3's render tests (``src/render/tests/test_renders.py``) compare a
render's XYZ mean :math:`m` at n spp with the reference :math:`r` and its
XYZ variance :math:`v` (floored at 1e-4) pixel by pixel:
:math:`z = |m - r| \sqrt{n / \max(v, 10^{-4})}`, two-sided normal p-value,
each tested at the Sidak level :math:`1 - (1 - 0.01)^{1/N}` for N pixels;
the scene passes when at least 99.75 % of the pixel-channels pass. The
reference's noise and the render's own variance do not enter.
"""

from __future__ import annotations

import numpy as np
from scipy import stats as sps

SIGNIFICANCE = 0.01
PASS_FRACTION = 0.9975
VARIANCE_FLOOR = 1e-4


def z_rule(mean_xyz: np.ndarray, ref_xyz: np.ndarray, ref_var_xyz: np.ndarray, spp: int) -> dict:
    """Mitsuba's verdict: ``{'passed', 'failing', 'allowed', 'min_p'}`` (failing pixel-channels, the most allowed)."""
    n_pix = mean_xyz.shape[0] * mean_xyz.shape[1]
    z = np.abs(mean_xyz.astype(np.float64) - ref_xyz) * np.sqrt(spp / np.maximum(ref_var_xyz, VARIANCE_FLOOR))
    p = 2.0 * sps.norm.sf(z)
    level = 1.0 - (1.0 - SIGNIFICANCE) ** (1.0 / n_pix)
    ok = int(np.count_nonzero(p > level))
    failing = p.size - ok
    return {"passed": bool(ok / 3 >= PASS_FRACTION * n_pix), "failing": int(failing),
            "allowed": int(np.floor(p.size - 3 * PASS_FRACTION * n_pix)), "min_p": float(p.min())}
