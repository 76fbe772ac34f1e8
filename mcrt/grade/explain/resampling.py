r"""A resolution mistake: the image rendered at 1/k the resolution and enlarged.

The model image is R box-filtered to 1/k of the resolution (the expected
value of the smaller render), enlarged by repeating pixels (blocks of k x k
equal pixels, whose share in the hand-in the words give) or bilinearly, for
k in :data:`FACTORS`.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit


#: Resolution factors of the resampling family.
FACTORS = (2, 4)


def _blocks_equal(S: np.ndarray, k: int) -> float:
    """Share of k x k blocks whose pixels are all equal (the trace of nearest-neighbour enlarging)."""
    h, w = S.shape[:2]
    if h % k or w % k:
        return 0.0
    b = S.reshape(h // k, k, w // k, k, -1)
    return float(np.mean(np.all(b == b[:, :1, :, :1], axis=(1, 3, 4))))


def resampling(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The image rendered at 1/k the resolution and enlarged, by nearest neighbour or bilinearly."""
    from scipy.ndimage import zoom

    from mcrt.stats.tiles import block_means

    h, w = fit.R.shape[:2]
    out = []
    for k in FACTORS:
        if h % k or w % k:
            continue
        low = block_means(fit.R, k)
        near = np.repeat(np.repeat(low, k, axis=0), k, axis=1)
        lin = zoom(low, (k, k, 1), order=1, mode="nearest", grid_mode=True)
        eq = _blocks_equal(fit.S, k)
        blocks = f" ({100 * eq:.0f} % of its {k} x {k} blocks are one colour)" if eq > 0.5 else ""
        out.append(Candidate("resampling", f"enlarged {k}x (nearest)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by repeating pixels{blocks}", fit.model(near), 1,
                              value={"factor": k, "method": "nearest", "equal_blocks": eq}, change=near - fit.R))
        out.append(Candidate("resampling", f"enlarged {k}x (bilinear)", f"the image rendered at {w // k} x {h // k} "
                              f"pixels and enlarged {k} times by bilinear interpolation", fit.model(lin), 1,
                              value={"factor": k, "method": "bilinear"}, change=lin - fit.R))
    return out


resampling.name = "resampling"
