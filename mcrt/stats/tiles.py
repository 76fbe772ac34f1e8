r"""Tiles: sums and means of an image over square blocks of pixels.

Every statistic that pools pixels into tiles goes through :func:`tile_sums`.
Tile ``(ty, tx)`` (tile row, tile column) of edge ``tile`` covers pixel rows
``ty*tile .. min(H, (ty+1)*tile) - 1`` and the matching columns; partial
tiles at the bottom and right edges are kept, with the pixels they have.
``tile = 0`` makes the whole image one tile. For a tile T of ``|T|`` pixels

.. math::

    S_T(x) = \sum_{i \in T} x_i, \qquad \bar x_T = S_T(x) / |T|,

computed channel by channel for (H, W, ...) arrays.
"""

from __future__ import annotations

import numpy as np

__all__ = ["tile_sums", "tile_counts", "tile_means", "block_means", "tile_box", "tile_expand"]


def _step(n: int, tile: int) -> int:
    """Tile edge along an axis of ``n`` pixels (``tile = 0``: the whole axis)."""
    return tile if tile > 0 else max(n, 1)


def tile_sums(x: np.ndarray, tile: int) -> np.ndarray:
    """Sums :math:`S_T(x)` of an (H, W, ...) array over tiles, shape (tiles_y, tiles_x, ...).

    Parameters
    ----------
    x : numpy.ndarray
        At least two dimensions; the first two are pixel rows and columns.
    tile : int
        Tile edge in pixels; 0 for the whole image.
    """
    h, w = x.shape[:2]
    rows = np.arange(0, h, _step(h, tile))
    cols = np.arange(0, w, _step(w, tile))
    return np.add.reduceat(np.add.reduceat(x, rows, axis=0), cols, axis=1)


def tile_counts(h: int, w: int, tile: int) -> np.ndarray:
    """Pixel count :math:`|T|` of every tile of an h x w image, shape (tiles_y, tiles_x), float64."""
    return tile_sums(np.ones((h, w)), tile)


def tile_means(x: np.ndarray, tile: int) -> np.ndarray:
    r"""Tile means :math:`\bar x_T = S_T(x) / |T|` of an (H, W, ...) array, shape (tiles_y, tiles_x, ...).

    Where H and W are multiples of ``tile`` this is the block mean (box
    filter and decimation by ``tile``).
    """
    h, w = x.shape[:2]
    n = tile_counts(h, w, tile)
    return tile_sums(x, tile) / n.reshape(n.shape + (1,) * (x.ndim - 2))


def block_means(x: np.ndarray, k: int) -> np.ndarray:
    """Means over k x k blocks of an (H, W, ...) array whose H and W are multiples of ``k``, shape (H/k, W/k, ...).

    The box filter and decimation of a change of resolution by ``k``:
    :func:`tile_means` of edge ``k`` where no tile is partial. ``k = 1``
    returns ``x`` itself; a ValueError where H or W is not a multiple of
    ``k`` (a resolution that is not an integer multiple has no block means).
    """
    if k == 1:
        return x
    h, w = x.shape[:2]
    if k < 1 or h % k or w % k:
        raise ValueError(f"a {w}x{h} image does not divide into {k}x{k} blocks")
    return tile_means(x, k)


def tile_box(h: int, w: int, tile: int, ty: int, tx: int) -> tuple[int, int, int, int]:
    """Pixel bounds ``(y0, y1, x0, x1)`` (end exclusive) of tile ``(ty, tx)`` of an h x w image."""
    sy, sx = _step(h, tile), _step(w, tile)
    return ty * sy, min(h, (ty + 1) * sy), tx * sx, min(w, (tx + 1) * sx)


def tile_expand(t: np.ndarray, h: int, w: int, tile: int) -> np.ndarray:
    """Per-tile values (tiles_y, tiles_x, ...) spread over the pixels of an h x w image, shape (h, w, ...).

    Every pixel gets the value of the tile that covers it (partial edge
    tiles included): the inverse of pooling, for per-pixel use of a tile
    statistic and for drawing tile maps.
    """
    return np.repeat(np.repeat(t, _step(h, tile), axis=0), _step(w, tile), axis=1)[:h, :w]
