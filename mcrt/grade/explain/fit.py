r"""The chi^2 a model image leaves against a hand-in: what every family of mistakes is scored by."""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import FLOOR

#: Largest contribution of one term to chi^2 (z^2): heavy-tailed noise (a firefly the noise model did not
#: foresee) counts as a clear mismatch, not as a hundred.
CAP = 100.0
#: Uncertainty (pixels) in where an edge lies, in every model image.
EDGE = 0.05


class Fit:
    r"""chi^2 of model images against the student's image, each term capped at CAP (see the module docstring).

    The chi^2 sums two levels: single pixels (what a shift, a blur or an
    edge changes) and the means of ``tile`` x ``tile`` tiles (what a smooth
    bias of a per cent changes: a single pixel's noise hides it, a tile's
    mean does not). Every chi^2 here, that of the reference included, has
    the same pixel weights
    :math:`1 / (\tilde V + W + (f R)^2 + (\epsilon |\nabla R|)^2)`:
    :math:`\tilde V` is the noise variance raised to its 3x3 mean where that
    is larger (a pixel's variance estimated from a few thousand heavy-tailed
    samples is usually too small; its neighbours' share the rare bright
    paths), and :math:`\epsilon` = EDGE pixel of uncertainty in where an edge
    lies (no model image puts a light's edge exactly). A tile mean's variance
    is the sum of its pixels' over the count squared, plus the floor.
    """

    def __init__(self, S, R, V, ok, W, tile: int = 8):
        from scipy.ndimage import uniform_filter

        self.S, self.R, self.ok = S, R, ok
        V = np.where(np.isfinite(V), V, 0.0)
        V = np.maximum(V, uniform_filter(V, (3, 3, 1), mode="nearest"))
        self.V = V  # the noise variance of S - R per pixel, as the weights take it
        gy, gx = np.gradient(R, axis=(0, 1))
        edge = EDGE**2 * (gx**2 + gy**2)
        var = V + W + (FLOOR * R) ** 2 + edge
        self.w = np.where(ok, 1.0 / np.maximum(var, 1e-30), 0.0)
        self.D = np.where(ok, S - R, 0.0)
        self.t = max(1, min(int(tile), *R.shape[:2]))
        self.hc, self.wc = (R.shape[0] // self.t) * self.t, (R.shape[1] // self.t) * self.t
        cnt = self.blocks(ok.astype(np.float64))
        self.cnt = np.maximum(cnt, 1.0)
        r_t = self.blocks(np.where(ok, R, 0.0)) / self.cnt
        v_t = self.blocks(np.where(ok, var, 0.0)) / self.cnt**2 + (FLOOR * r_t) ** 2
        self.wt = np.where(cnt >= 2, 1.0 / np.maximum(v_t, 1e-30), 0.0)
        self.Dt = self.blocks(self.D) / self.cnt
        self.n = int(np.count_nonzero(ok)) + int(np.count_nonzero(cnt >= 2))
        self.chi0 = self.delta(0.0)

    def blocks(self, x: np.ndarray) -> np.ndarray:
        """Sums over the tiles of x (..., H, W, C), cropped to whole tiles: (..., H/t, W/t, C)."""
        x = x[..., : self.hc, : self.wc, :]
        t = self.t
        sh = x.shape[:-3] + (self.hc // t, t, self.wc // t, t, x.shape[-1])
        return x.reshape(sh).sum(axis=(-4, -2))

    def tile_means(self, dm: np.ndarray) -> np.ndarray:
        return self.blocks(np.where(self.ok, dm, 0.0)) / self.cnt

    def delta(self, dm) -> float:
        """chi^2 of M = R + dm (pixels and tiles)."""
        dt = self.tile_means(np.broadcast_to(dm, self.D.shape)) if not np.isscalar(dm) else dm
        return float(np.sum(np.minimum((self.D - dm) ** 2 * self.w, CAP)) +
                     np.sum(np.minimum((self.Dt - dt) ** 2 * self.wt, CAP)))

    def terms(self, dm) -> np.ndarray:
        """Each capped term of :meth:`delta` (pixels, then tiles), flattened: what two model images are compared by
        term by term (:func:`mcrt.grade.adequacy.closeness`)."""
        dm = np.broadcast_to(np.asarray(dm, np.float64), self.D.shape)
        dt = self.tile_means(dm)
        return np.concatenate([np.minimum((self.D - dm) ** 2 * self.w, CAP).ravel(),
                               np.minimum((self.Dt - dt) ** 2 * self.wt, CAP).ravel()])

    def model(self, m: np.ndarray) -> float:
        return self.delta(m - self.R)

    def irls(self, dm) -> np.ndarray:
        """Weights of a least-squares step that caps like chi^2: w where z^2 < CAP, w CAP / z^2 beyond (pixels)."""
        z2 = (self.D - dm) ** 2 * self.w
        return self.w * np.minimum(1.0, CAP / np.maximum(z2, 1e-300))


#: Nodes and weights of the probabilists' Gauss-Hermite rule: E[g(Z)] for a standard normal Z as a weighted sum.
_GH_Z, _GH_W = np.polynomial.hermite_e.hermegauss(5)
_GH_W = _GH_W / _GH_W.sum()


def bent_noise(f, R: np.ndarray, var: np.ndarray) -> np.ndarray:
    """The variance of f(X) for X a noisy render's value: mean R, variance ``var``, log-normal (a Monte Carlo mean is
    never negative and is skewed to the bright side). A curve on the values bends the render's noise with it: a steep
    one (an encoding near black) grows it, a flat one (a clamp, a tone map's shoulder) shrinks it."""
    R = np.maximum(R, 0.0)
    sl2 = np.log1p(np.maximum(var, 0.0) / np.maximum(R * R, 1e-300))
    sl = np.sqrt(sl2)
    vals = np.stack([f(R * np.exp(sl * z - 0.5 * sl2)) for z in _GH_Z])
    m = np.tensordot(_GH_W, vals, axes=1)
    return np.maximum(np.tensordot(_GH_W, vals**2, axes=1) - m**2, 0.0)


def curve_change(fit: Fit, f) -> tuple[float, np.ndarray, np.ndarray]:
    """(chi^2, change, noise variance) of the hand-in as curve f on the render's values: what a curve's candidate is
    scored by, its predicted change f(R) - R, and the noise the remainder test allows it (:func:`bent_noise`). The
    mean is taken as f(R): the shift a curve's bend puts on a noisy pixel's mean is of second order, and the
    variance held here can be the one measured on the hand-in, which the mistake itself inflates."""
    change = f(np.maximum(fit.R, 0.0)) - fit.R
    return fit.delta(change), change, bent_noise(f, fit.R, fit.V)


def refine(grid: np.ndarray, err: np.ndarray, i: int) -> float:
    """The minimum of the parabola through the grid's best point and its neighbours."""
    if 0 < i < len(grid) - 1:
        y0, y1, y2 = err[i - 1], err[i], err[i + 1]
        den = y0 - 2 * y1 + y2
        if den > 0:
            return float(grid[i] + 0.5 * (y0 - y2) / den * (grid[1] - grid[0]))
    return float(grid[i])
