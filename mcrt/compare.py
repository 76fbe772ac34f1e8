"""``mcrt compare``: read two image files, compare them under a policy, write the verdict.

A thin layer over :mod:`mcrt.stats`: :func:`compare_files` reads the files
(:func:`mcrt.imageio.read_image`), fills in what the files lack where asked
to (sample counts, a borrowed variance), runs :func:`mcrt.stats.compare`
under the chosen policy and writes the results: the report printed by
:func:`report_lines`, the heat map of t (:func:`write_heatmap`) and the JSON
report (:func:`write_json`). The exit codes are :mod:`mcrt.exitcodes`'s:
0 consistent, 1 different, 2 unusable input.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import IO

import numpy as np

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.film import RenderResult
from mcrt.stats import POLICIES, Comparison, StatsError, compare

__all__ = ["report_lines", "heatmap_rgb", "write_heatmap", "write_json", "compare_files"]

# Saturation of the heat map's colour scale, in units of t.
_HEATMAP_T_MAX = 5.0


def report_lines(c: Comparison, limit: int = 20) -> list[str]:
    """Multi-line, human-readable report of a comparison: the verdict, up to
    ``limit`` failing tests with their pixel ranges, the largest effect, the
    largest |t| and smallest p-value, the whole-image difference."""
    lines = [c.headline()]
    if not c.passed:
        lines.append("failing tests (tile row, col; pixel rows/cols inclusive), smallest p first:")
        for f in c.failing_tiles[:limit]:
            y0, y1, x0, x1 = c.tile_box(f.ty, f.tx)
            lines.append(
                f"  tile ({f.ty},{f.tx}) {f.channel}  rows {y0}-{y1 - 1} cols {x0}-{x1 - 1}  "
                f"t={f.t:+.2f}  p={f.p:.3g}  A-B={f.diff:+.4g} ({100 * f.rel_diff:+.2f} %)"
            )
        if len(c.failing_tiles) > limit:
            lines.append(f"  ... and {len(c.failing_tiles) - limit} more")
        e = c.largest_effect
        lines.append(f"largest effect: {100 * e.rel_diff:+.2f} % at tile ({e.ty},{e.tx}) {e.channel}")
    m = c.max_abs_t
    lines.append(f"largest |t|: {abs(m.t):.2f} at tile ({m.ty},{m.tx}) {m.channel}; min p-value: {c.min_p:.3g}")
    g = ", ".join(f"{ch} {100 * v:+.3f} %" for ch, v in zip(c.channel_names, c.global_rel_diff))
    lines.append(f"whole-image mean, A relative to B: {g}")
    n_det = int(np.count_nonzero(c.deterministic))
    if n_det:
        lines.append(f"{n_det} tests had zero variance on both sides and were compared for equality")
    return lines


def heatmap_rgb(c: Comparison, scale: int = 1) -> np.ndarray:
    r"""The heat map of a comparison as an (H*scale, W*scale, 3) uint8 array.

    Each tile shows its signed t (the channel with the largest |t|) as
    :math:`s = \mathrm{clip}(t / 5, -1, 1)`, colour
    :math:`(1 - s^-,\ 1 - |s|,\ 1 - s^+)`: white at 0, red where A is
    brighter, blue where A is darker, saturating at |t| = 5. Rejected tiles
    are outlined in black.
    """
    scale = max(1, int(scale))
    t = np.nan_to_num(c.t, nan=0.0, posinf=1e9, neginf=-1e9)
    idx = np.argmax(np.abs(t), axis=2)
    tmap = np.take_along_axis(t, idx[:, :, None], axis=2)[:, :, 0]
    s = np.clip(tmap / _HEATMAP_T_MAX, -1.0, 1.0)
    pos, neg = np.maximum(s, 0), np.maximum(-s, 0)
    rgb = np.stack([1 - neg, 1 - pos - neg, 1 - pos], axis=-1)
    tiles = np.round(255 * rgb).astype(np.uint8)
    px = c.tile * scale
    h, w = c.shape[0] * scale, c.shape[1] * scale
    img = np.repeat(np.repeat(tiles, px, axis=0), px, axis=1)[:h, :w].copy()
    bw = max(1, scale // 2)
    for ty, tx in zip(*np.nonzero(c.rejected.any(axis=2))):
        y0, y1, x0, x1 = (v * scale for v in c.tile_box(int(ty), int(tx)))
        img[y0:y1, x0:x0 + bw] = 0
        img[y0:y1, x1 - bw:x1] = 0
        img[y0:y0 + bw, x0:x1] = 0
        img[y1 - bw:y1, x0:x1] = 0
    return img


def write_heatmap(c: Comparison, path, scale: int = 1) -> Path:
    """Write :func:`heatmap_rgb` as a PNG to ``path`` (folders created); returns the path."""
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(heatmap_rgb(c, scale)).save(path)
    return path


def write_json(c: Comparison, path) -> Path:
    """Write :meth:`Comparison.to_dict` as JSON to ``path`` (folders created); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(c.to_dict(), indent=1))
    return path


def _describe(r: RenderResult, path) -> str:
    h, w = r.mean.shape[:2]
    var = "variance" if r.variance is not None else "NO variance"
    spp = f"{r.spp} spp" if r.spp else "spp unknown"
    who = f", {r.renderer}" if r.renderer else ""
    return f"{path} ({w}x{h}, {spp}, {var}{who})"


def _borrow_variance(sides: dict[str, tuple[RenderResult, object]], min_spp: int, allowed: bool, out: IO[str]) -> None:
    """Give the one side without per-sample variance the other's (``--assume-variance-from other``).

    Raises :class:`StatsError` naming the side and the option to pass when
    neither side has a variance, when borrowing is not ``allowed``, or when
    the borrowing side's spp is unknown.
    """
    missing = [n for n, (r, _) in sides.items() if r.variance is None]
    if not missing:
        return
    if len(missing) == 2:
        raise StatsError(
            f"neither image has a per-sample variance ({sides['A'][1]}, {sides['B'][1]}); "
            "render them with mcrt (or Mitsuba's 'moment' integrator) so that each keeps its variance"
        )
    lack = missing[0]
    other = "B" if lack == "A" else "A"
    r, path = sides[lack]
    donor = sides[other][0]
    if not allowed:
        raise StatsError(
            f"image {lack} ({path}) has no per-sample variance; render it again with mcrt, or "
            f"pass --assume-variance-from other (with --spp-{lack.lower()} N if its spp is unknown) "
            f"to borrow image {other}'s variance"
        )
    if donor.variance.shape != r.mean.shape:
        raise StatsError(f"images differ in shape: A is {sides['A'][0].mean.shape}, B is {sides['B'][0].mean.shape}")
    if not r.spp or r.spp < max(2, min_spp):
        raise StatsError(f"image {lack} ({path}) has no usable spp ({r.spp}); give it with --spp-{lack.lower()} N")
    r.variance = donor.variance.copy()
    print(f"note: image {lack} uses image {other}'s per-sample variance (approximation)", file=out)


def compare_files(
    path_a,
    path_b,
    *,
    policy: str = "independent",
    min_spp: int = 2,
    heatmap=None,
    heatmap_scale: int = 1,
    json_path=None,
    assume_variance_from_other: bool = False,
    spp_a: int | None = None,
    spp_b: int | None = None,
    out: IO[str] | None = None,
    err: IO[str] | None = None,
    **options,
) -> int:
    """Compare two image files under ``policy``, print the verdict, return an exit code.

    Reads both files, runs :func:`mcrt.stats.compare` (A is the image under
    test, B the other; under ``policy='reference-floor'`` B is the high-spp
    reference) and prints the inputs, the verdict and :func:`report_lines`
    to ``out`` (stdout). Optionally writes the heat map (PNG, ``heatmap``)
    and the :meth:`Comparison.to_dict` report (JSON, ``json_path``).
    ``options`` (``alpha``, ``tile``, ``channels``, ``correction``) and
    ``min_spp`` are those of :func:`mcrt.stats.compare`.

    Missing variance or sample count: the test needs each side's own
    per-sample variance and spp. ``spp_a`` / ``spp_b`` override the sample
    counts read from the files. If one side lacks variance, the comparison
    is refused (exit 2) with a message naming that side, unless
    ``assume_variance_from_other`` is set: then that side borrows the other
    image's per-sample variance (its spp must be known or given). This is an
    approximation: two estimators of the same image generally differ in
    variance, and with heavy-tailed per-pixel estimates the borrowed variance
    can make the test false-alarm; rendering the image again with variance is
    the remedy.

    Returns
    -------
    int
        :data:`mcrt.exitcodes.EXIT_OK` (0, consistent),
        :data:`~mcrt.exitcodes.EXIT_FAILED` (1, different) or
        :data:`~mcrt.exitcodes.EXIT_UNUSABLE` (2, the inputs cannot be compared).

    Raises
    ------
    ValueError
        An unknown policy or an invalid option (the command line maps it to
        exit code 2).
    """
    out = sys.stdout if out is None else out
    err = sys.stderr if err is None else err
    from mcrt.imageio import ImageError, read_image

    try:
        a = read_image(path_a)
        b = read_image(path_b)
    except (ImageError, OSError) as e:
        print(f"error: {e}", file=err)
        return EXIT_UNUSABLE

    sides = {"A": (a, path_a), "B": (b, path_b)}
    for (r, _), override in zip(sides.values(), (spp_a, spp_b)):
        if override is not None:
            r.spp = int(override)
    try:
        _borrow_variance(sides, min_spp, assume_variance_from_other, out)
        for name, (r, path) in sides.items():
            if not r.spp:
                raise StatsError(f"image {name} ({path}) does not record its spp; give it with --spp-{name.lower()} N")
        c = compare(a, b, policy=policy, min_spp=min_spp, **options)
    except StatsError as e:
        print(f"error: {e}", file=err)
        return EXIT_UNUSABLE

    if c.policy != "independent":
        print(f"note: policy {c.policy}: {POLICIES[c.policy]}", file=out)

    print(f"A: {_describe(a, path_a)}", file=out)
    print(f"B: {_describe(b, path_b)}", file=out)
    for line in report_lines(c):
        print(line, file=out)
    if heatmap is not None:
        print(f"heat map: {write_heatmap(c, heatmap, scale=heatmap_scale)}", file=out)
    if json_path is not None:
        print(f"report: {write_json(c, json_path)}", file=out)
    return EXIT_OK if c.passed else EXIT_FAILED
