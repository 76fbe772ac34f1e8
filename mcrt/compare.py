"""``mcrt compare``: two renders in, compared under a policy, the verdict out.

A thin layer over :mod:`mcrt.stats`. Each side is an image file
(:func:`mcrt.image_files.read_image`; OpenEXR through :func:`mcrt.image_files.read_exr`,
which also reads Mitsuba's ``moment`` integrator), a
:class:`~mcrt.film.RenderResult`, or a NumPy mean with its per-sample
variance and spp given alongside (:func:`as_result`, :func:`image`).
:func:`compare_files` fills in what the inputs lack where asked to (sample
counts, a borrowed variance), refuses inputs whose headers show different
cameras, scenes, resolutions or max depths (:func:`check_headers`), runs
:func:`mcrt.stats.compare` under the chosen policy and writes the results:
the report printed by :func:`report_lines`, the heat map of t
(:func:`write_heatmap`) and the JSON report (:func:`write_json`). The exit
codes are :mod:`mcrt.exitcodes`'s: 0 consistent, 1 different, 2 unusable
input.

Which policy (:mod:`mcrt.stats.policy`):

* ``independent`` (default): two independent renders, each with its own
  variance: two integrators or renderers, two seeds, sample counts of the
  same order. Use it whenever B is not a high-spp render of A's estimator.
* ``reference-floor``: A against a high-spp reference B *of the same
  estimator* (a committed Mitsuba reference against a fresh Mitsuba or
  ``path`` render): A's per-sample variance is raised to B's where lower,
  because a low-spp render that misses rare bright paths underestimates its
  variance where its mean is low, and correct renders are then rejected.

Relative differences are *symmetric*: (A - B) / ((|A| + |B|) / 2), per tile
and for the whole image; positive where A is brighter.
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path
from typing import IO

import numpy as np

from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.film import RenderResult
from mcrt.stats import POLICIES, Comparison, StatsError, compare, variance_dof

__all__ = ["report_lines", "noiseless_lines", "heatmap_rgb", "write_heatmap", "write_json", "image", "as_result", "check_headers",
           "HEADER_FIELDS", "HeaderMismatch", "compare_files"]

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
                f"t={f.t:+.2f}  p={f.p:.3g}  A-B={f.diff:+.4g} ({100 * f.rel_diff:+.2f} % symmetric)"
            )
        if len(c.failing_tiles) > limit:
            lines.append(f"  ... and {len(c.failing_tiles) - limit} more")
        e = c.largest_effect
        lines.append(f"largest effect: {100 * e.rel_diff:+.2f} % (symmetric) at tile ({e.ty},{e.tx}) {e.channel}")
    m = c.max_abs_t
    lines.append(f"largest |t|: {abs(m.t):.2f} at tile ({m.ty},{m.tx}) {m.channel}; min p-value: {c.min_p:.3g}")
    g = ", ".join(f"{ch} {100 * v:+.3f} %" for ch, v in zip(c.channel_names, c.global_rel_diff))
    lines.append(f"whole-image mean, symmetric relative difference (A-B)/mean(|A|,|B|): {g}")
    lines += noiseless_lines(c)
    return lines


def noiseless_lines(c: Comparison) -> list[str]:
    """What the tests of noiseless tiles (zero variance on both sides, compared for equality) found, apart.

    A difference there is no Monte Carlo noise: an offset of the reference
    (a constant 1.0 stored as 1.00108), a different background, a
    different emitter seen directly. Says how many differ and by how much,
    and when ``rtol`` accepted some.
    """
    n = c.noiseless()
    if not n["tests"]:
        return []
    size = f"{100 * n['largest_rel_diff']:.3g} %"
    lines = [f"noiseless tests (zero variance on both sides, compared for equality within rtol {c.rtol:g}): "
             f"{n['tests']}, {n['rejected']} differ; largest difference {size} (symmetric)"]
    if n["rejected"]:
        noisy = c.n_rejected - n["rejected"]
        lines.append(f"  {n['rejected']} of the {c.n_rejected} rejected tests are noiseless ({noisy} noisy): a difference "
                     f"without noise, up to {size}; if it is a known offset, --rtol {_round_up(n['largest_rel_diff'])} "
                     "accepts it")
    if n["accepted_by_rtol"]:
        lines.append(f"  note: --rtol {c.rtol:g} accepted {n['accepted_by_rtol']} noiseless tests that differ by more "
                     f"than float32 rounding (up to {size})")
    return lines


def _round_up(x: float) -> str:
    """A tolerance just above ``x`` with two significant digits (0.001084 -> '0.0011')."""
    import math

    if x <= 0:
        return "0"
    e = math.floor(math.log10(x)) - 1
    return f"{math.ceil(x / 10**e) * 10**e:.2g}"


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
    kind = str((r.extra or {}).get("variance_method", "samples")).partition(":")[0]  # mcrt.variance_method
    var = "NO variance" if r.variance is None else "variance" if variance_dof(r) == r.spp - 1 else \
        f"variance of {variance_dof(r) + 1} {kind}, {variance_dof(r)} df"
    spp = f"{r.spp} spp" if r.spp else "spp unknown"
    who = f", {r.renderer}" if r.renderer else ""
    cam = f", camera {r.camera}" if r.camera else ""
    return f"{path} ({w}x{h}, {spp}, {var}{who}{cam})"


def image(mean, variance=None, spp: int = 0, *, seed: int = 0, max_depth: int = 0, renderer: str = "unknown",
          scene_hash: str = "", camera: str = "", wall_time: float = 0.0) -> RenderResult:
    """A :class:`RenderResult` from your own renderer's arrays: mean and per-sample variance (H, W, 3), and spp.

    The per-sample variance is that of one sample (not of the mean): the
    unbiased estimate (S2 - S1^2 / n) / (n - 1) from per-pixel sums of x and
    x^2. Provenance fields default to "unknown" values (max depth 0, empty
    camera and scene hash), which :func:`check_headers` does not check.
    """
    mean = np.asarray(mean, dtype=np.float32)
    var = None if variance is None else np.asarray(variance, dtype=np.float32)
    return RenderResult(mean=mean, variance=var, spp=int(spp), seed=int(seed), max_depth=int(max_depth),
                        renderer=renderer, scene_hash=scene_hash, camera=camera, wall_time=float(wall_time))


def as_result(x, *, name: str = "A", variance=None, spp: int | None = None, variance_kind: str = "auto") -> RenderResult:
    """One side of a comparison as a RenderResult: a file path, a RenderResult, or a NumPy mean.

    A path is read (``spp`` replaces a sample count the file lacks, and
    scales a ``moment`` file's variance, :func:`mcrt.image_files.read_exr`); a
    RenderResult is used as is (a copy with ``spp``/``variance`` replaced
    when given); an array is the mean and needs ``variance`` and ``spp``
    alongside. ``variance`` may also be the path of a variance EXR, read by
    :func:`mcrt.image_files.read_variance_exr` as ``variance_kind`` says
    (Mitsuba's reference variance, an XYZ variance, by default where the
    file says Mitsuba wrote it). Raises :class:`StatsError` naming the side
    and what is missing, :class:`mcrt.image_files.ImageError` for an unreadable
    file or a variance with negative or non-finite entries.
    """
    from dataclasses import replace

    imageio = importlib.import_module("mcrt.image_files")  # what sys.modules holds (tests stand in for it)
    if isinstance(variance, (str, bytes)) or hasattr(variance, "__fspath__"):
        r = as_result(x, name=name, spp=spp)
        var, note = imageio.read_variance_exr(variance, mean=r.mean, kind=variance_kind)
        r.variance = var
        r.extra = {**r.extra, "variance": f"{variance}: {note}"}
        return r
    if variance is not None:
        variance = np.asarray(variance, dtype=np.float32)
        if variance.shape == np.shape(getattr(x, "mean", x)):
            for what, bad in (("negative", variance < 0), ("non-finite", ~np.isfinite(variance))):
                if bad.any():
                    raise StatsError(f"image {name}: its given variance has {int(bad.sum())} {what} entries")

    if isinstance(x, RenderResult):
        changes = {k: v for k, v in (("spp", spp), ("variance", variance)) if v is not None}
        return replace(x, **changes)  # a copy: filling in what it lacks must not change the caller's object
    if isinstance(x, (str, bytes)) or hasattr(x, "__fspath__"):
        # An EXR given its spp: read_exr scales a 'moment' file's variance by n / (n - 1).
        exr = spp is not None and str(x).lower().endswith(".exr") and hasattr(imageio, "read_exr")
        r = imageio.read_exr(x, spp=spp) if exr else imageio.read_image(x)
        if spp is not None:
            r.spp = int(spp)
        if variance is not None:
            r.variance = np.asarray(variance, dtype=np.float32)
        return r
    if isinstance(x, np.ndarray) or hasattr(x, "__array__"):
        a = name.lower()
        if variance is None or spp is None:
            lacks = " and ".join(w for w, v in (("variance", variance), ("spp", spp)) if v is None)
            raise StatsError(f"image {name} is a bare array: give its per-sample {lacks} alongside "
                             f"(variance_{a}=..., spp_{a}=...), or pass mcrt.compare.image(mean, variance, spp)")
        return image(x, variance, spp)
    raise StatsError(f"image {name}: expected a file path, a RenderResult or a NumPy array, got {type(x).__name__}")


#: The provenance fields two compared renders must share; ``check_headers`` refuses a difference in any.
HEADER_FIELDS = ("resolution", "camera", "scene_hash", "max_depth")


class HeaderMismatch(StatsError):
    """Two renders whose headers say they are not images of the same thing (different camera, scene, ...)."""


def check_headers(a: RenderResult, b: RenderResult, name_a="A", name_b="B", allow=()) -> None:
    """Refuse two renders whose recorded resolution, camera, scene hash or max depth differ.

    A field is compared only where both sides record it (a camera or scene
    hash is not empty, a max depth is not 0, which files without our
    attributes read as); ``allow`` names fields (of :data:`HEADER_FIELDS`,
    or ``'all'``) to compare anyway. A different resolution is always
    refused (there is nothing to compare pixel by pixel). Raises
    :class:`HeaderMismatch` with one line naming both inputs and the field.
    """
    allow = set(HEADER_FIELDS) - {"resolution"} if "all" in allow else set(allow)
    unknown = allow - set(HEADER_FIELDS)
    if unknown:
        raise ValueError(f"unknown header field {sorted(unknown)[0]!r} (have {', '.join(HEADER_FIELDS)}, all)")
    checks = [("resolution", a.mean.shape[:2], b.mean.shape[:2], True)]
    checks += [(f, getattr(a, f), getattr(b, f), getattr(a, f) not in ("", None) and getattr(b, f) not in ("", None))
               for f in ("camera", "scene_hash")]
    checks.append(("max_depth", a.max_depth, b.max_depth, a.max_depth != 0 and b.max_depth != 0))
    for field_name, va, vb, known in checks:
        if known and va != vb and field_name not in allow:
            if field_name == "resolution":
                va, vb = f"{va[1]}x{va[0]}", f"{vb[1]}x{vb[0]}"
                hint = "render both at one resolution"
            else:
                hint = f"pass --allow-mismatch {field_name} (allow_mismatch=('{field_name}',)) to compare anyway"
            raise HeaderMismatch(f"{name_a} and {name_b} differ in {field_name}: {va} against {vb}; {hint}")


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
    variance_a=None,
    variance_b=None,
    variance_kind: str = "auto",
    allow_mismatch=(),
    out: IO[str] | None = None,
    err: IO[str] | None = None,
    **options,
) -> int:
    """Compare two renders under ``policy``, print the verdict, return an exit code.

    ``path_a`` and ``path_b`` are each a file, a RenderResult or a NumPy mean
    (:func:`as_result`: an array needs ``variance_*`` and ``spp_*``). Runs
    :func:`mcrt.stats.compare` (A is the image under test, B the other;
    under ``policy='reference-floor'`` B is the high-spp reference of A's
    estimator: the module docstring says which policy to use when) and
    prints the inputs, the verdict and :func:`report_lines` to ``out``
    (stdout). Optionally writes the heat map (PNG, ``heatmap``) and the
    :meth:`Comparison.to_dict` report (JSON, ``json_path``). ``options``
    (``alpha``, ``tile``, ``channels``, ``correction``) and ``min_spp`` are
    those of :func:`mcrt.stats.compare`.

    Variance: an mcrt EXR records how its variance was estimated
    (``mcrt.variance_method``: per sample, or 'replicates:R' for a
    stratified render, :mod:`mcrt.samplers`); the test gives each side the
    degrees of freedom it has (:func:`mcrt.stats.variance_dof`).

    Headers: inputs whose recorded resolution, camera, scene hash or max
    depth differ are refused (exit 2, one line naming both and the field,
    :func:`check_headers`) unless the field is in ``allow_mismatch``.

    Variance files: ``variance_a`` / ``variance_b`` may name an EXR
    holding that side's per-sample variance (``--variance-a/-b FILE``),
    read as ``variance_kind`` says (:data:`mcrt.image_files.VARIANCE_KINDS`):
    Mitsuba's reference variance (an XYZ variance written through the
    XYZ-to-RGB matrix, partly negative) is turned back into XYZ and bounded
    in RGB; a plain variance with negative or non-finite entries is refused
    (exit 2). ``rtol`` (an option of :func:`mcrt.stats.compare`) accepts a
    relative difference between noiseless tiles; the report says when it
    did (:func:`noiseless_lines`).

    Missing variance or sample count: the test needs each side's own
    per-sample variance and spp. ``spp_a`` / ``spp_b`` override the sample
    counts read from the files (and scale the variance of a ``moment``
    integrator's file). If one side lacks variance, the comparison
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
    imageio = importlib.import_module("mcrt.image_files")  # what sys.modules holds (tests stand in for it)

    label_a = _label(path_a, "A")
    label_b = _label(path_b, "B")
    try:
        a = as_result(path_a, name="A", variance=variance_a, spp=spp_a, variance_kind=variance_kind)
        b = as_result(path_b, name="B", variance=variance_b, spp=spp_b, variance_kind=variance_kind)
    except (imageio.ImageError, OSError, StatsError) as e:
        print(f"error: {e}", file=err)
        return EXIT_UNUSABLE

    sides = {"A": (a, label_a), "B": (b, label_b)}
    try:
        check_headers(a, b, label_a, label_b, allow=allow_mismatch)
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

    print(f"A: {_describe(a, label_a)}", file=out)
    print(f"B: {_describe(b, label_b)}", file=out)
    for name, r in (("A", a), ("B", b)):
        if "variance" in r.extra:
            print(f"note: {name}'s variance: {r.extra['variance']}", file=out)
    for line in report_lines(c):
        print(line, file=out)
    if heatmap is not None:
        print(f"heat map: {write_heatmap(c, heatmap, scale=heatmap_scale)}", file=out)
    if json_path is not None:
        print(f"report: {write_json(c, json_path)}", file=out)
    return EXIT_OK if c.passed else EXIT_FAILED


def _label(x, name: str) -> str:
    """How an input is named in messages: its path, or 'image A (a RenderResult of path)'."""
    if isinstance(x, (str, bytes)) or hasattr(x, "__fspath__"):
        return str(x)
    if isinstance(x, RenderResult):
        return f"image {name} ({x.renderer}, seed {x.seed})"
    return f"image {name} (an array)"
