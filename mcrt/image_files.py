"""Images in and out: OpenEXR renders with provenance, PFM, Radiance HDR, PNG; reading PPM, BMP and TGA.

Our own format is a single-part scanline OpenEXR file (float32, ZIP
compressed) holding

* the mean as channels ``R``, ``G``, ``B``;
* the per-sample variance as ``variance.R``, ``variance.G``, ``variance.B``
  (left out when the render has none);
* the provenance of :class:`~mcrt.film.RenderResult` as header attributes
  ``spp``, ``seed``, ``max_depth`` (int), ``renderer``, ``scene_hash``,
  ``camera`` (string), ``wall_time`` and ``compile_time`` (double), and every
  entry of ``extra`` as a string attribute ``mcrt.<key>``. An integer that
  does not fit an EXR int (32 bits, for example a 64-bit seed) is stored as
  its decimal string and read back as an int.

:func:`read_exr` reads these back bit-exactly, and also plain RGB/RGBA EXRs
from other tools (half or float; alpha ignored; ``spp = 0`` marks a file
without our attributes). :func:`read_image` reads any supported format into
a :class:`RenderResult`; files from other formats get ``variance=None``,
``spp=0`` and ``renderer='unknown'``.

All arrays are (height, width, 3) float32 linear RGB, top row first. Every
problem with a file is an :class:`ImageError` whose one-line message names
the file, e.g. ``sub/alice.exr: truncated or corrupt OpenEXR file (...)``.
Writers are atomic: the image goes to a temporary file in the target folder
which then replaces the target, so a failed write never leaves a half-written
file where a good one stood.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import sys
import tempfile
import threading
import warnings
from pathlib import Path
from typing import Callable

import numpy as np
import OpenEXR
from PIL import Image, ImageDraw, ImageFont

from mcrt.film import RenderResult
from mcrt.srgb import srgb_eotf, srgb_eotf_slope, srgb_oetf  # noqa: F401  (this module's PNG API uses them; others import them here)
from mcrt.util import atomic

PathLike = str | os.PathLike

EXR_MAGIC = b"\x76\x2f\x31\x01"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

# Header attributes of our EXR files; extra entries get this prefix.
EXTRA_PREFIX = "mcrt."
_INT_ATTRS = ("spp", "seed", "max_depth")
_STR_ATTRS = ("renderer", "scene_hash", "camera")
_INT32 = (-(2**31), 2**31 - 1)

MAGENTA = (255, 0, 255)

#: The most pixels any reader decodes (4096 x 4096): every reader checks the header's size first, so a small file
#: that declares a huge image (a 280 KB PNG of 12000 x 12000) is refused before it takes gigabytes to decode.
MAX_PIXELS = 1 << 24


class ImageError(ValueError):
    """A file that cannot be read or written; the one-line message names it."""


# --------------------------------------------------------------------------
# Helpers: messages, reading bytes, atomic writes, array checks
# --------------------------------------------------------------------------


def _one_line(text: object, limit: int = 200) -> str:
    s = " ".join(str(text).split())
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _read_bytes(path: PathLike, size: int = -1) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(size)
    except FileNotFoundError:
        raise ImageError(f"{os.fspath(path)}: no such file") from None
    except IsADirectoryError:
        raise ImageError(f"{os.fspath(path)}: is a directory, not an image") from None
    except OSError as e:
        raise ImageError(f"{os.fspath(path)}: cannot read ({_one_line(e.strerror or e)})") from None


def _check_pixels(path: PathLike, width: int, height: int) -> None:
    """Refuse an image whose header declares more than :data:`MAX_PIXELS` pixels, before anything is decoded."""
    if width <= 0 or height <= 0:
        raise ImageError(f"{os.fspath(path)}: the image has no pixels ({width}x{height})")
    if width * height > MAX_PIXELS:
        raise ImageError(f"{os.fspath(path)}: {width}x{height} pixels is more than the {MAX_PIXELS:,} pixels an image "
                         "may have here")


def _atomic_write(path: PathLike, write: Callable[[str], None]) -> None:
    """Run ``write(tmp)`` on a fresh file beside ``path``, then move it over ``path`` (:func:`mcrt.util.atomic.replacing`).

    ``path`` is either the old file or the complete new one; a failure is
    an :class:`ImageError` naming the file.
    """
    path = os.fspath(path)
    try:
        with atomic.replacing(path) as tmp:
            write(tmp)
    except ImageError:
        raise
    except OSError as e:
        raise ImageError(f"{path}: cannot write ({_one_line(e.strerror or e)})") from None
    except Exception as e:
        raise ImageError(f"{path}: cannot write ({_one_line(e)})") from e


def _write_bytes(path: PathLike, data: bytes) -> None:
    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(data)

    _atomic_write(path, write)


def _rgb_array(path: PathLike, rgb: np.ndarray, what: str = "image", grey: bool = False) -> np.ndarray:
    """``rgb`` as a float32 array of shape (H, W, 3) (or (H, W) if ``grey`` allows it)."""
    a = np.asarray(rgb)
    ok = a.ndim == 3 and a.shape[2] == 3
    if grey and (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 1)):
        a, ok = a.reshape(a.shape[:2]), True
    if not ok or a.shape[0] == 0 or a.shape[1] == 0:
        want = "(height, width, 3) or (height, width)" if grey else "(height, width, 3)"
        raise ImageError(f"{os.fspath(path)}: {what} has shape {a.shape}, expected {want}")
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise ImageError(f"{os.fspath(path)}: {what} has dtype {a.dtype}, expected floats")
    return np.ascontiguousarray(a, dtype=np.float32)


# --------------------------------------------------------------------------
# OpenEXR
# --------------------------------------------------------------------------

_capture_lock = threading.Lock()


@contextlib.contextmanager
def _captured_library_output():
    """Collect what OpenEXR prints while reading, so it can go into an ImageError.

    The C library reports errors on file descriptor 2 and the Python binding
    prints warnings to ``sys.stdout``; both are captured here. The caller
    puts the text back on stderr if the read succeeds (``log['ok'] = True``).
    """
    log: dict = {"text": "", "ok": False}
    out = io.StringIO()
    with _capture_lock, tempfile.TemporaryFile() as tmp:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            sys.stderr.flush()
        try:
            saved = os.dup(2)
        except OSError:  # no stderr to capture
            saved = None
        if saved is not None:
            try:
                os.dup2(tmp.fileno(), 2)
            except OSError:
                os.close(saved)
                saved = None
        try:
            with contextlib.redirect_stdout(out):
                yield log
        finally:
            if saved is not None:
                os.dup2(saved, 2)
                os.close(saved)
            tmp.seek(0)
            native = tmp.read().decode("utf-8", "replace")
            log["text"] = out.getvalue() + native
            if log["ok"]:  # nothing went wrong: pass the output on
                sys.stdout.write(out.getvalue())
                if native and saved is not None:
                    os.write(2, native.encode())


def _library_detail(text: str, path: str) -> str:
    """The most telling line of OpenEXR's output, without the repeated file name."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    if not lines:
        return ""
    line = lines[-1]
    name = os.path.basename(path)
    for prefix in (path + ":", name + ":"):
        if line.startswith(prefix):
            line = line[len(prefix):].strip()
    return _one_line(line, 160)


def write_exr(path: PathLike, result: RenderResult) -> None:
    """Write a render as a float32 OpenEXR file (ZIP compressed), atomically.

    Channels ``R, G, B`` hold the mean, ``variance.R, variance.G,
    variance.B`` the per-sample variance (omitted if ``result.variance`` is
    None); the provenance fields become header attributes as described in the
    module docstring. :func:`read_exr` returns an equal RenderResult.
    """
    path = os.fspath(path)
    mean = _rgb_array(path, result.mean, "mean")
    channels = {c: np.ascontiguousarray(mean[..., i]) for i, c in enumerate("RGB")}
    if result.variance is not None:
        var = _rgb_array(path, result.variance, "variance")
        if var.shape != mean.shape:
            raise ImageError(f"{path}: variance has shape {var.shape}, mean has {mean.shape}")
        channels.update({f"variance.{c}": np.ascontiguousarray(var[..., i]) for i, c in enumerate("RGB")})

    header: dict = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for name in _INT_ATTRS:
        v = int(getattr(result, name))
        header[name] = v if _INT32[0] <= v <= _INT32[1] else str(v)
    for name in _STR_ATTRS:
        header[name] = str(getattr(result, name))
    # A 1-element float64 array is how the binding writes a double attribute;
    # a Python float would become a 32-bit float attribute.
    header["wall_time"] = np.array([float(result.wall_time)], np.float64)
    if result.compile_time is not None:
        header["compile_time"] = np.array([float(result.compile_time)], np.float64)
    for key, value in result.extra.items():
        header[EXTRA_PREFIX + str(key)] = str(value)

    _atomic_write(path, lambda tmp: _write_exr_file(tmp, header, channels))


def _write_exr_file(tmp: str, header: dict, channels: dict) -> None:
    OpenEXR.File(header, channels).write(tmp)


def read_exr(path: PathLike, *, spp: int | None = None) -> RenderResult:
    """Read an OpenEXR file written by :func:`write_exr` or by another tool.

    ``spp`` gives the sample count of a file that does not record it (it
    replaces the file's ``spp`` attribute); a file of Mitsuba's ``moment``
    integrator needs it for its variance (:func:`_read_moment_channels`).

    The first part must hold channels ``R, G, B`` (half or float); ``A`` is
    ignored, ``variance.R/G/B`` become the variance, other channels are
    ignored and listed in ``extra['exr.ignored_channels']``. Missing
    attributes read as ``spp=0`` (unknown), ``seed=0``, ``max_depth=0``,
    ``renderer='unknown'``, empty strings, ``wall_time=0`` and
    ``compile_time=None``.

    Raises
    ------
    ImageError
        Missing, truncated or corrupt file, or a channel layout without
        R, G, B (the message lists the channels found).
    """
    path = os.fspath(path)
    head = _read_bytes(path, 4)
    if head != EXR_MAGIC:
        raise ImageError(f"{path}: not an OpenEXR file (bad magic number)")
    log = {"text": ""}
    try:
        with _captured_library_output() as log:
            head_only = OpenEXR.File(path, header_only=True)
            if len(head_only.parts):
                _check_pixels(path, *_exr_shape(path, dict(head_only.header(0)))[::-1])
            f = OpenEXR.File(path, separate_channels=True)
            parts = len(f.parts)
            if parts:
                header = dict(f.header(0))
                channels = dict(f.channels(0))
            log["ok"] = parts > 0
    except ImageError:
        raise
    except Exception as e:
        detail = _library_detail(log["text"], path) or _one_line(e, 160)
        raise ImageError(f"{path}: truncated or corrupt OpenEXR file ({detail})") from None
    if not parts:
        detail = _library_detail(log["text"], path) or "no readable part"
        raise ImageError(f"{path}: truncated or corrupt OpenEXR file ({detail})")

    names = sorted(channels)
    shape = _exr_shape(path, header)
    moment = _read_moment_channels(path, channels, shape, spp if spp is not None else _attr_int(path, header, "spp"))
    if moment is None and not {"R", "G", "B"} <= set(names):
        raise ImageError(f"{path}: expected channels R, G, B (optionally A), found {', '.join(names) or 'none'}")
    var_names = ("variance.R", "variance.G", "variance.B")
    extra = {k[len(EXTRA_PREFIX):]: _attr_str(path, header, k, "") for k in header if k.startswith(EXTRA_PREFIX)}
    if moment is not None:  # Mitsuba's 'moment' integrator: mean and variance from the XYZ moments
        mean, variance, note, used = moment
        extra["exr.moment"] = note
        var_names = (*var_names, *used, "R", "G", "B")
    else:
        mean = _exr_stack(path, channels, ("R", "G", "B"), shape)
        present = [n for n in var_names if n in channels]
        if present and len(present) < 3:
            raise ImageError(f"{path}: incomplete variance channels, found {', '.join(present)}")
        variance = _exr_stack(path, channels, var_names, shape) if present else None
        if variance is not None:
            check_variance(path, variance, "variance channels")

    ignored = [n for n in names if n not in ("R", "G", "B", "A") and n not in var_names]
    if ignored:
        extra["exr.ignored_channels"] = ",".join(ignored)
    if "generatedBy" in header:  # which program wrote the file (Mitsuba's references: their variance's layout)
        extra["exr.generatedBy"] = _attr_str(path, header, "generatedBy", "")
    compile_time = _attr_float(path, header, "compile_time", None)
    return RenderResult(
        mean=mean,
        variance=variance,
        spp=int(spp) if spp is not None else _attr_int(path, header, "spp"),
        seed=_attr_int(path, header, "seed"),
        max_depth=_attr_int(path, header, "max_depth"),
        renderer=_attr_str(path, header, "renderer", "unknown"),
        scene_hash=_attr_str(path, header, "scene_hash", ""),
        camera=_attr_str(path, header, "camera", ""),
        wall_time=_attr_float(path, header, "wall_time", 0.0),
        compile_time=compile_time,
        extra=extra,
    )


#: The channels of Mitsuba's ``moment`` integrator around a nested integrator given as ``nested`` (first
#: moments, second moments, XYZ). Mitsuba 3.9.1 names the nested integrator of an XML scene ``_arg_0``
#: (``_arg_0.X`` / ``m2__arg_0.X``); :func:`moment_prefix` finds any such name.
MOMENT_CHANNELS = (("nested.X", "nested.Y", "nested.Z"), ("m2_nested.X", "m2_nested.Y", "m2_nested.Z"))

#: CIE XYZ -> linear sRGB / Rec. 709 RGB (D65), the standard matrix (IEC 61966-2-1), as Mitsuba's xyz_to_srgb.
XYZ_TO_RGB = np.array([[3.240479, -1.537150, -0.498535],
                       [-0.969256, 1.875991, 0.041556],
                       [0.055648, -0.204043, 1.057311]])

#: Linear sRGB -> CIE XYZ, the inverse of :data:`XYZ_TO_RGB` (its middle row is the Rec. 709 luminance).
RGB_TO_XYZ = np.linalg.inv(XYZ_TO_RGB)

#: A second moment kept in float32 loses about this fraction of m1^2 to rounding when m1^2 is taken from it
#: (accumulated over thousands of samples): an XYZ variance down to -CANCELLATION * max(m1)^2 is a noiseless
#: pixel's rounding, read as 0; one below it is refused. Mitsuba's committed references reach 2.0e-3.
CANCELLATION = 4e-3


def moment_prefix(path: str, names) -> str | None:
    """The nested integrator's name in a ``moment`` EXR (``nested``, ``_arg_0``, ...), or None for other files.

    A name p qualifies when the file has a second moment ``m2_p.X/Y/Z``,
    or is ``nested`` (the dictionary's name) with any channel. Raises
    :class:`ImageError` when the file holds more than one (which to use is
    not knowable) or an incomplete set (the missing channels named).
    """
    names = set(names)
    prefixes = {n[3:-2] for n in names if n.startswith("m2_") and n[-2:] in (".X", ".Y", ".Z")}
    prefixes |= {"nested"} if any(n.startswith(("nested.", "m2_nested.")) for n in names) else set()
    prefixes = sorted(prefixes)
    if not prefixes:
        return None
    if len(prefixes) > 1:
        raise ImageError(f"{path}: moments of several integrators ({', '.join(prefixes)}); expected one")
    p = prefixes[0]
    missing = [n for n in (*(f"{p}.{c}" for c in "XYZ"), *(f"m2_{p}.{c}" for c in "XYZ")) if n not in names]
    if missing:
        raise ImageError(f"{path}: incomplete moment channels, missing {', '.join(missing)}")
    return p


def repair_xyz_variance(path: str, var_xyz: np.ndarray, mean_xyz: np.ndarray, what: str, *,
                        zero_small: bool = False) -> tuple[np.ndarray, int]:
    r"""An XYZ per-sample variance with float32 cancellation removed; refuses what cannot be rounding.

    Negative entries :math:`v \ge -c \max_j m_j^2` (c = :data:`CANCELLATION`,
    :math:`m_j` the pixel's XYZ mean) are what :math:`m_2 - m_1^2` in float32
    leaves for a noiseless pixel: they become 0. A more negative or a
    non-finite entry is not a variance: :class:`ImageError` naming the file,
    the count and the worst pixel. ``zero_small`` also reads positive
    entries up to that bound as 0 (a high-spp reference: such a value cannot
    be told from a noiseless pixel's rounding, and the pixel then counts as
    noiseless in a comparison). Returns ``(variance, entries repaired)``.
    """
    bad = ~np.isfinite(var_xyz) | ~np.isfinite(mean_xyz)
    if bad.any():
        y, x, _ = np.argwhere(bad)[0]
        raise ImageError(f"{path}: {int(bad.sum())} non-finite values in the {what} (first at row {y}, column {x})")
    floor = -CANCELLATION * np.max(mean_xyz * mean_xyz, axis=-1, keepdims=True)
    wrong = var_xyz < floor
    if wrong.any():
        y, x, c = np.argwhere(wrong)[np.argmin((var_xyz - floor)[wrong])]
        raise ImageError(f"{path}: {int(wrong.sum())} negative XYZ variances beyond float32 rounding in the {what} "
                         f"(worst {var_xyz[y, x, c]:.3g} at row {y}, column {x}, channel {'XYZ'[c]}, mean {mean_xyz[y, x, c]:.3g})")
    neg = (var_xyz <= -floor) if zero_small else (var_xyz < 0)
    return np.where(neg, 0.0, var_xyz), int(np.count_nonzero(neg & (var_xyz != 0)))


def xyz_variance_to_rgb(var_xyz: np.ndarray) -> np.ndarray:
    r"""A per-channel RGB variance bound from a per-channel XYZ variance: :math:`\mathrm{sd}_R \le \sum_j |M_{Rj}|\, \mathrm{sd}_j`.

    The cross moments (E[XY], ...) are not kept, so the variance of
    :math:`R = \sum_j M_{Rj} X_j` is bounded by Cauchy-Schwarz: conservative
    (a comparison with it false-alarms less than nominal and detects less).
    """
    sd = np.sqrt(np.maximum(var_xyz, 0.0)) @ np.abs(XYZ_TO_RGB).T
    return sd * sd


def _read_moment_channels(path: str, channels: dict, shape: tuple[int, int], spp: int):
    r"""Mean and per-sample variance (linear RGB) of a ``moment`` integrator's EXR, or None for other files.

    The file holds per pixel the mean of each sample's X, Y, Z (``nested.*``,
    ``_arg_0.*``, ...: :func:`moment_prefix`) and of their squares
    (``m2_nested.*``), with a box filter. The mean is :data:`XYZ_TO_RGB`
    times (X, Y, Z). The per-sample variance of X is
    :math:`(m_2 - m_1^2)\, n / (n - 1)` (the unbiased estimate: ``spp`` = n
    must be known, from the file or given; without it the factor is left
    out and noted), float32 cancellation repaired or refused by
    :func:`repair_xyz_variance`, and bounded in RGB by
    :func:`xyz_variance_to_rgb`. Returns ``(mean, variance, note, channels used)``.
    """
    p = moment_prefix(path, channels)
    if p is None:
        return None
    first, second = tuple(f"{p}.{c}" for c in "XYZ"), tuple(f"m2_{p}.{c}" for c in "XYZ")
    m1 = _exr_stack(path, channels, first, shape).astype(np.float64)
    m2 = _exr_stack(path, channels, second, shape).astype(np.float64)
    var_xyz, repaired = repair_xyz_variance(path, m2 - m1 * m1, m1, f"moments {p}")
    fixed = f", {repaired} rounding-level negatives read as 0" if repaired else ""
    if spp and spp >= 2:
        var_xyz *= spp / (spp - 1)
        note = f"XYZ moments {p}, variance (m2 - m1^2) n/(n-1) with n = {spp}{fixed}, RGB sd bounded by sum |M| sd_XYZ"
    else:
        note = (f"XYZ moments {p}, variance m2 - m1^2 (spp unknown: not scaled by n/(n-1)){fixed}, "
                "RGB sd bounded by sum |M| sd_XYZ")
    mean = m1 @ XYZ_TO_RGB.T
    return mean.astype(np.float32), xyz_variance_to_rgb(var_xyz).astype(np.float32), note, (*first, *second)


def check_variance(path: str, variance: np.ndarray, what: str) -> None:
    """Refuse a per-sample variance with negative or non-finite entries: :class:`ImageError` naming the file,
    the count and the first pixel (a variance of Mitsuba's references is read by :func:`read_variance_exr`)."""
    for bad, kind in ((~np.isfinite(variance), "non-finite"), (variance < 0, "negative")):
        if bad.any():
            y, x, c = np.argwhere(bad)[0]
            hint = ("; a Mitsuba reference's variance file holds an XYZ variance: read it as such "
                    "(--variance-kind mitsuba)" if kind == "negative" else "")
            raise ImageError(f"{path}: {int(bad.sum())} {kind} entries in the {what} (first at row {y}, column {x}, "
                             f"channel {'RGB'[c]}: {variance[y, x, c]:.3g}){hint}")


#: How a variance file given apart from its mean is read (:func:`read_variance_exr`).
VARIANCE_KINDS = {
    "auto": "mitsuba for a file whose header says Mitsuba wrote it (generatedBy), else rgb",
    "rgb": "the file's R, G, B (or variance.R/G/B) are a per-sample RGB variance; negative entries are refused",
    "mitsuba": "Mitsuba's reference variance: a per-sample XYZ variance pushed through the XYZ-to-RGB matrix "
               "(so partly negative); turned back into XYZ, float32 rounding repaired, bounded in RGB",
}


def read_variance_exr(path: PathLike, *, mean: np.ndarray, kind: str = "auto", space: str = "rgb"
                      ) -> tuple[np.ndarray, str]:
    r"""A per-sample variance image given apart from its mean (``mcrt compare --variance-b FILE``).

    ``mean`` is the (H, W, 3) linear RGB mean the variance belongs to.
    ``kind`` (:data:`VARIANCE_KINDS`): ``'rgb'`` reads the channels as
    they are and refuses negative or non-finite entries
    (:func:`check_variance`). ``'mitsuba'`` reads what Mitsuba's render-test
    suite writes as ``<name>_ref_rgb_var.exr``: the per-sample XYZ variance
    :math:`m_2 - m_1^2` of its ``moment`` integrator, converted to RGB by
    the XYZ-to-RGB matrix *as if it were a colour* (hence up to 41 % negative
    entries; no variance transforms that way). The conversion is linear and
    invertible, so :data:`RGB_TO_XYZ` gives back the XYZ variance exactly;
    rounding-level negatives are repaired by :func:`repair_xyz_variance`.
    Entries within float32 rounding of 0 are read as 0 (``zero_small``).
    ``space='xyz'`` returns that XYZ variance, exact per channel (compare in
    XYZ, as Mitsuba's own test does); ``'rgb'`` returns the Cauchy-Schwarz
    bound :func:`xyz_variance_to_rgb` (conservative). Returns
    ``(variance, note)``, the note saying which reading was used.
    """
    path = os.fspath(path)
    if kind not in VARIANCE_KINDS:
        raise ValueError(f"variance kind must be one of {', '.join(VARIANCE_KINDS)}, got {kind!r}")
    if space not in ("rgb", "xyz"):
        raise ValueError(f"space must be 'rgb' or 'xyz', got {space!r}")
    raw = read_exr(path)
    header_by = raw.extra.get("exr.generatedBy", "")
    if kind == "auto":
        kind = "mitsuba" if header_by.startswith("Mitsuba") else "rgb"
    data = raw.variance if raw.variance is not None else raw.mean
    data = data.astype(np.float64)
    if data.shape != mean.shape:
        raise ImageError(f"{path}: variance is {data.shape[1]}x{data.shape[0]}, its mean {mean.shape[1]}x{mean.shape[0]}")
    if kind == "rgb":
        check_variance(path, data, "variance")
        if space == "xyz":
            raise ValueError(f"{path}: a per-channel RGB variance has no exact XYZ variance (the cross terms are not kept)")
        return data.astype(np.float32), "per-sample RGB variance as stored"
    mean_xyz = mean.astype(np.float64) @ RGB_TO_XYZ.T
    var_xyz, repaired = repair_xyz_variance(path, data @ RGB_TO_XYZ.T, mean_xyz, "variance (read back as XYZ)",
                                            zero_small=True)
    neg = int(np.count_nonzero(data < 0))
    note = (f"Mitsuba's XYZ variance ({neg} of {data.size} stored entries negative) turned back into XYZ"
            + (f", {repaired} within float32 rounding of 0 (|v| <= {CANCELLATION:g} max m^2) read as 0" if repaired else ""))
    if space == "xyz":
        return var_xyz.astype(np.float32), note
    return xyz_variance_to_rgb(var_xyz).astype(np.float32), note + ", RGB sd bounded by sum |M| sd_XYZ (conservative)"


def read_mitsuba_reference(mean_path: PathLike, var_path: PathLike | None = None, *, spp: int,
                           space: str = "rgb") -> RenderResult:
    """A reference of Mitsuba's render-test suite, ``<name>_ref_rgb.exr`` with ``<name>_ref_rgb_var.exr``.

    ``var_path`` defaults to the mean's name with ``_var`` before ``.exr``.
    The files do not record their spp: give it (Mitsuba's reference
    generator renders 32000 spp by default). The variance is read by
    :func:`read_variance_exr` (kind ``'mitsuba'``). ``space='xyz'`` returns
    mean and variance in CIE XYZ (``extra['channels'] = 'XYZ'``), the mean
    turned back by :data:`RGB_TO_XYZ`, as Mitsuba's own test reads it.
    """
    mean_path = os.fspath(mean_path)
    if var_path is None:
        root, ext = os.path.splitext(mean_path)
        var_path = f"{root}_var{ext}"
    r = read_exr(mean_path)
    variance, note = read_variance_exr(var_path, mean=r.mean, kind="mitsuba", space=space)
    r.variance, r.spp, r.renderer = variance, int(spp), "mitsuba-reference"
    r.extra["variance"] = f"{os.fspath(var_path)}: {note}"
    r.extra["spp"] = f"{spp} (given: the reference files do not record it)"
    if space == "xyz":
        r.mean = (r.mean.astype(np.float64) @ RGB_TO_XYZ.T).astype(np.float32)
        r.extra["channels"] = "XYZ"
    return r


def _exr_shape(path: str, header: dict) -> tuple[int, int]:
    try:
        lo, hi = header["dataWindow"]
        return int(hi[1] - lo[1] + 1), int(hi[0] - lo[0] + 1)
    except (KeyError, TypeError, ValueError, IndexError):
        raise ImageError(f"{path}: OpenEXR header has no usable dataWindow") from None


def _exr_stack(path: str, channels: dict, names: tuple[str, ...], shape: tuple[int, int]) -> np.ndarray:
    planes = []
    for n in names:
        px = channels[n].pixels
        if px is None or px.shape != shape:
            got = None if px is None else px.shape
            raise ImageError(f"{path}: channel {n} has shape {got}, expected {shape} (subsampled channels are not supported)")
        if px.dtype not in (np.float16, np.float32):
            cast = " (integers: the values cast to an integer type before writing)" if px.dtype.kind in "iu" else ""
            raise ImageError(f"{path}: channel {n} holds {px.dtype}{cast}, expected half or float")
        planes.append(px.astype(np.float32))
    return np.stack(planes, axis=-1)


def _safe_repr(v: object) -> str:
    try:
        return _one_line(repr(v), 60)
    except Exception:  # opaque attributes with undecodable type names
        return f"a {type(v).__name__}"


def _attr_str(path: str, header: dict, name: str, default: str) -> str:
    v = header.get(name, default)
    if isinstance(v, str):
        return v
    try:
        return str(v)
    except Exception:  # e.g. an opaque attribute of unknown type
        raise ImageError(f"{path}: attribute {name} cannot be read as text") from None


def _attr_int(path: str, header: dict, name: str) -> int:
    if name not in header:
        return 0
    v = header[name]
    try:
        if isinstance(v, (int, np.integer)):
            return int(v)
        if isinstance(v, str):
            return int(v.strip())
        f = float(np.asarray(v, dtype=np.float64).reshape(-1)[0]) if np.size(v) == 1 else math.nan
        if f.is_integer():
            return int(f)
    except (ValueError, TypeError, OverflowError):
        pass
    raise ImageError(f"{path}: attribute {name}: expected an integer, got {_safe_repr(v)}")


def _attr_float(path: str, header: dict, name: str, default: float | None) -> float | None:
    if name not in header:
        return default
    v = header[name]
    try:
        if isinstance(v, str):
            return float(v.strip())
        if np.size(v) == 1:
            return float(np.asarray(v, dtype=np.float64).reshape(-1)[0])
    except (ValueError, TypeError):
        pass
    raise ImageError(f"{path}: attribute {name}: expected a number, got {_safe_repr(v)}")


# --------------------------------------------------------------------------
# PFM: Portable Float Map
# --------------------------------------------------------------------------

_PFM_HEADER = re.compile(rb"(PF|Pf)\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s")


#: Bytes a PFM file may hold after its data (a writer's trailing newline) before it is an error.
_PFM_SLACK = 16


def read_pfm(path: PathLike, *, swap_byte_order: bool = False) -> np.ndarray:
    """Read a Portable Float Map: (H, W, 3) float32, top row first.

    ``PF`` is colour, ``Pf`` greyscale (replicated to three channels). A
    negative scale means little-endian data, a positive one big-endian; rows
    are stored bottom to top. A scale magnitude other than 1 multiplies the
    data (as pbrt does). ``swap_byte_order`` reads the data in the other byte
    order than the header declares (not the spec: for a grader that checks
    whether a header's sign contradicts its data).
    """
    path = os.fspath(path)
    data = _read_bytes(path)
    w, h, scale, colour, m = _pfm_header(path, data)
    if w == 0 or h == 0 or scale == 0 or not math.isfinite(scale):
        raise ImageError(f"{path}: PFM header gives {w}x{h} pixels and scale {scale}")
    _check_pixels(path, w, h)
    c = 3 if colour else 1
    n = w * h * c * 4
    body = data[m.end(): m.end() + n]
    if len(body) < n:
        raise ImageError(f"{path}: truncated PFM file ({len(body)} of {n} data bytes)")
    extra = len(data) - m.end() - n
    if extra > _PFM_SLACK:  # data the header does not declare: a wrong size or channel count, not a trailing newline
        kind = "RGB ('PF')" if colour else "greyscale ('Pf')"
        more = (f"; it holds 3 times the data, as an RGB image does: write the header 'PF'"
                if not colour and extra == 2 * n else "")
        raise ImageError(f"{path}: PFM file holds {extra} bytes more than its header declares ({w}x{h} {kind}){more}")
    little = (scale < 0) != swap_byte_order
    a = np.frombuffer(body, dtype="<f4" if little else ">f4").reshape(h, w, c)
    a = a[::-1].astype(np.float32)
    if abs(scale) != 1.0:
        with np.errstate(over="ignore", invalid="ignore"):
            a *= np.float32(abs(scale))
    return np.ascontiguousarray(np.repeat(a, 3, axis=2) if c == 1 else a)


def pfm_scale(path: PathLike) -> float:
    """The scale of a PFM file's header (its sign declares the byte order: negative little-endian)."""
    path = os.fspath(path)
    return _pfm_header(path, _read_bytes(path))[2]


def _pfm_header(path: str, data: bytes):
    """(width, height, scale, colour, the header's match) of a PFM file's bytes; ImageError when it is not one."""
    m = _PFM_HEADER.match(data)
    if not m:
        raise ImageError(f"{path}: not a PFM file (expected 'PF' or 'Pf', width, height, scale)")
    colour = m.group(1) == b"PF"
    w, h = int(m.group(2)), int(m.group(3))
    try:
        scale = float(m.group(4))
    except ValueError:
        raise ImageError(f"{path}: PFM scale {m.group(4).decode()!r} is not a number") from None
    return w, h, scale, colour, m


def write_pfm(path: PathLike, rgb: np.ndarray, *, little_endian: bool = True) -> None:
    """Write a Portable Float Map atomically: ``PF`` for (H, W, 3), ``Pf`` for (H, W).

    Scale -1 (little-endian) by default, +1 (big-endian) with
    ``little_endian=False``; rows bottom to top as the format requires.
    """
    a = _rgb_array(path, rgb, grey=True)
    h, w = a.shape[:2]
    magic = "PF" if a.ndim == 3 else "Pf"
    head = f"{magic}\n{w} {h}\n{-1.0 if little_endian else 1.0}\n".encode()
    body = np.ascontiguousarray(a[::-1], dtype="<f4" if little_endian else ">f4").tobytes()
    _write_bytes(path, head + body)


# --------------------------------------------------------------------------
# Radiance RGBE (.hdr, .pic)
# --------------------------------------------------------------------------

_HDR_RES = re.compile(rb"([-+])([XY])\s+(\d+)\s+([-+])([XY])\s+(\d+)")


def read_hdr(path: PathLike) -> np.ndarray:
    """Read a Radiance RGBE picture: (H, W, 3) float32, top row first.

    Scanlines may be flat, new-style run-length encoded, or use old-style
    repeat runs. A pixel (r, g, b, e) with e > 0 decodes to
    ``(r, g, b) * 2**(e - 136)`` (the convention of rgbe.c, stb_image and
    OpenImageIO; e = 0 is black). ``EXPOSURE=`` lines, which record a factor
    already applied to the pixels, are divided out. All eight orientations of
    the resolution line are honoured.
    """
    path = os.fspath(path)
    data = _read_bytes(path)
    if not data.startswith(b"#?"):
        raise ImageError(f"{path}: not a Radiance HDR file (no '#?' signature)")
    end = data.find(b"\n\n", 0, 1 << 16)
    if end < 0:
        raise ImageError(f"{path}: Radiance header has no end (blank line)")
    exposure = 1.0
    for line in data[:end].split(b"\n")[1:]:
        line = line.strip()
        if line.startswith(b"FORMAT="):
            fmt = line[7:].strip()
            if fmt != b"32-bit_rle_rgbe":
                raise ImageError(f"{path}: unsupported Radiance format {fmt.decode(errors='replace')!r} (only 32-bit_rle_rgbe)")
        elif line.startswith(b"EXPOSURE="):
            try:
                exposure *= float(line[9:])
            except ValueError:
                raise ImageError(f"{path}: bad EXPOSURE line {line.decode(errors='replace')!r}") from None
    nl = data.find(b"\n", end + 2)
    m = _HDR_RES.fullmatch(data[end + 2: nl].strip()) if nl >= 0 else None
    if not m or m.group(2) == m.group(5):
        raise ImageError(f"{path}: bad Radiance resolution line")
    n1, n2 = int(m.group(3)), int(m.group(6))
    if n1 == 0 or n2 == 0:
        raise ImageError(f"{path}: Radiance picture has no pixels ({n1}x{n2})")
    _check_pixels(path, n2, n1)
    if n1 * n2 > 64 * len(data) + (1 << 20):  # more than run-length coding can pack in
        raise ImageError(f"{path}: truncated or corrupt Radiance HDR file ({n1}x{n2} pixels in {len(data)} bytes)")
    rgbe = _hdr_scanlines(path, data, nl + 1, n1, n2)  # (n1, n2, 4): rows along the first axis

    e = rgbe[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)
    img = rgbe[..., :3] * scale[..., None]
    if exposure != 1.0 and exposure > 0:
        img /= exposure
    # Y axis: '-' means the first index is the top row; X axis: '+' means left first.
    if m.group(1 if m.group(2) == b"Y" else 4) == b"+":
        img = img[::-1] if m.group(2) == b"Y" else img[:, ::-1]
    if m.group(4 if m.group(5) == b"X" else 1) == b"-":
        img = img[:, ::-1] if m.group(5) == b"X" else img[::-1]
    if m.group(2) == b"X":
        img = img.transpose(1, 0, 2)
    return np.ascontiguousarray(img, dtype=np.float32)


def _hdr_scanlines(path: str, data: bytes, pos: int, rows: int, width: int) -> np.ndarray:
    out = np.empty((rows, width, 4), np.uint8)
    n = len(data)

    def truncated() -> ImageError:
        return ImageError(f"{path}: truncated Radiance HDR file (scanline {y} of {rows})")

    for y in range(rows):
        if 8 <= width <= 32767 and data[pos: pos + 2] == b"\x02\x02" and pos + 4 <= n and data[pos + 2] < 128:
            if (data[pos + 2] << 8 | data[pos + 3]) != width:
                raise ImageError(f"{path}: scanline {y} has run-length width {data[pos + 2] << 8 | data[pos + 3]}, expected {width}")
            pos += 4
            for c in range(4):
                chan = bytearray()
                while len(chan) < width:
                    if pos >= n:
                        raise truncated()
                    count = data[pos]
                    if count > 128:
                        if pos + 1 >= n:
                            raise truncated()
                        chan += data[pos + 1: pos + 2] * (count - 128)
                        pos += 2
                    else:
                        if pos + 1 + count > n:
                            raise truncated()
                        if count == 0:
                            raise ImageError(f"{path}: bad run-length data in scanline {y}")
                        chan += data[pos + 1: pos + 1 + count]
                        pos += 1 + count
                if len(chan) != width:
                    raise ImageError(f"{path}: run-length data overruns scanline {y}")
                out[y, :, c] = np.frombuffer(bytes(chan), np.uint8)
            continue
        # Flat pixels, possibly with old-style runs (1, 1, 1, k): repeat the last pixel.
        chunk = data[pos: pos + 4 * width]
        if len(chunk) < 4 * width:
            raise truncated()
        px = np.frombuffer(chunk, np.uint8).reshape(width, 4)
        if not np.any(np.all(px[:, :3] == 1, axis=1)):
            out[y] = px
            pos += 4 * width
        else:
            pos = _hdr_old_rle(path, data, pos, out[y], y)
    return out


def _hdr_old_rle(path: str, data: bytes, pos: int, row: np.ndarray, y: int) -> int:
    x, shift, width = 0, 0, row.shape[0]
    while x < width:
        p = data[pos: pos + 4]
        if len(p) < 4:
            raise ImageError(f"{path}: truncated Radiance HDR file (scanline {y})")
        pos += 4
        if p[0] == 1 and p[1] == 1 and p[2] == 1:
            count = p[3] << shift
            if x == 0 or x + count > width:
                raise ImageError(f"{path}: bad old-style run in scanline {y}")
            row[x: x + count] = row[x - 1]
            x += count
            shift += 8
        else:
            row[x] = np.frombuffer(p, np.uint8)
            x += 1
            shift = 0
    return pos


def _rgbe_encode(path: PathLike, a: np.ndarray) -> np.ndarray:
    a = a.astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ImageError(f"{os.fspath(path)}: cannot store NaN or infinite values in RGBE")
    a = np.maximum(a, 0.0)
    mx = a.max(axis=2)
    _, e = np.frexp(mx)  # mx = f * 2**e, f in [0.5, 1)
    e = e.astype(np.int64)
    top = np.floor(mx * np.ldexp(1.0, 8 - e) + 0.5)
    e = np.where(top >= 256, e + 1, e)  # rounding up reached 2**e
    if np.any((mx > 0) & (e > 127)):
        raise ImageError(f"{os.fspath(path)}: value too large for RGBE ({mx.max():g})")
    m = np.floor(a * np.ldexp(1.0, 8 - e)[..., None] + 0.5)
    out = np.zeros(a.shape[:2] + (4,), np.uint8)
    keep = (mx >= 1e-32) & (e >= -127)
    out[..., :3] = np.where(keep[..., None], np.clip(m, 0, 255), 0).astype(np.uint8)
    out[..., 3] = np.where(keep, e + 128, 0).astype(np.uint8)
    return out


def _rle_channel(row: np.ndarray) -> bytes:
    """New-style run-length encoding of one channel of one scanline."""
    out = bytearray()
    n = row.shape[0]
    starts = np.concatenate(([0], np.flatnonzero(row[1:] != row[:-1]) + 1))
    lengths = np.diff(np.concatenate((starts, [n])))
    lit = 0  # start of the pending literal span

    def literal(a: int, b: int) -> None:
        for s in range(a, b, 128):
            k = min(128, b - s)
            out.append(k)
            out.extend(row[s: s + k].tobytes())

    for s, k in zip(starts[lengths >= 4].tolist(), lengths[lengths >= 4].tolist()):
        literal(lit, s)
        while k > 0:
            r = min(127, k)
            out += bytes((128 + r, int(row[s])))
            s += r
            k -= r
        lit = s
    literal(lit, n)
    return bytes(out)


def write_hdr(path: PathLike, rgb: np.ndarray, *, rle: bool = True) -> None:
    """Write a Radiance RGBE picture atomically (``-Y H +X W``, top row first).

    Mantissas are rounded to nearest, so decoding with ``m * 2**(e - 136)``
    is within 1/256 of each pixel's largest channel. Negative values are
    stored as 0; NaN or infinity raises ImageError. With ``rle`` (default)
    scanlines of 8 to 32767 pixels are new-style run-length encoded,
    otherwise written flat.
    """
    a = _rgb_array(path, rgb)
    h, w = a.shape[:2]
    rgbe = _rgbe_encode(path, a)
    parts = [f"#?RADIANCE\n# written by mcrt\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()]
    if rle and 8 <= w <= 32767:
        marker = bytes((2, 2, w >> 8, w & 255))
        for y in range(h):
            parts.append(marker)
            parts.extend(_rle_channel(rgbe[y, :, c]) for c in range(4))
    else:
        parts.append(rgbe.tobytes())
    _write_bytes(path, b"".join(parts))


# --------------------------------------------------------------------------
# PNG
# --------------------------------------------------------------------------


def read_png(path: PathLike, linear: bool = False, *, swap_byte_order: bool = False) -> np.ndarray:
    """Read an 8- or 16-bit PNG as (H, W, 3) float32 linear RGB.

    Grey is replicated and alpha dropped. Code values are divided by 255 (or
    65535) and, unless ``linear``, decoded with the exact sRGB EOTF
    (:func:`srgb_eotf`; colour-space chunks such as gAMA or iCCP are not
    consulted). 8-bit (and lower) files are decoded by Pillow; 16-bit files
    by pypng, because Pillow reduces 16-bit RGB(A) and grey+alpha to 8 bits.
    ``swap_byte_order`` swaps each 16-bit sample's two bytes (not the spec,
    which is big-endian: for a grader that checks whether a program wrote
    its samples little-endian).
    """
    codes, maxval = _png_codes(os.fspath(path))
    if swap_byte_order and maxval == 65535:
        codes = codes.astype(np.uint16).byteswap()
    return _display_to_linear(codes, maxval, linear)


def _png_codes(path: str) -> tuple[np.ndarray, int]:
    """(H, W, 3) integer code values of a PNG and their maximum (255 or 65535)."""
    data = _read_bytes(path)
    if not data.startswith(PNG_MAGIC):
        raise ImageError(f"{path}: not a PNG file (bad signature)")
    if len(data) < 33 or data[12:16] != b"IHDR":
        raise ImageError(f"{path}: truncated or corrupt PNG file (no IHDR chunk)")
    _check_pixels(path, int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big"))
    if data[24] == 16:
        return _png16_decode(path, data), 65535
    return _pillow_rgb8(path, data, "PNG", ("1", "L", "LA", "P", "PA", "RGB", "RGBA")), 255


def _pillow_open(data: bytes, kind: str) -> Image.Image:
    """Pillow's header read. Its decompression-bomb warning is left out: :func:`_check_pixels` decides right after."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        return Image.open(io.BytesIO(data), formats=[kind])


def _pillow_rgb8(path: str, data: bytes, kind: str, modes: tuple[str, ...]) -> np.ndarray:
    """Decode an 8-bit image with Pillow to (H, W, 3) uint8 (grey replicated, palette expanded, alpha dropped)."""
    try:
        with _pillow_open(data, kind) as im:
            _check_pixels(path, *im.size)
            im.load()
            if im.mode not in modes:
                raise ImageError(f"{path}: unsupported {kind} pixel mode {im.mode}")
            rgb = im if im.mode == "RGB" else im.convert("RGB")
            return np.asarray(rgb, dtype=np.uint8)
    except ImageError:
        raise
    except Image.DecompressionBombError as e:  # past Pillow's own cap, before ours is asked
        raise ImageError(f"{path}: more than the {MAX_PIXELS:,} pixels an image may have here ({_one_line(e, 120)})") from None
    except Exception as e:
        raise ImageError(f"{path}: truncated or corrupt {kind} file ({_one_line(e, 160)})") from None


def _png16_decode(path: str, data: bytes) -> np.ndarray:
    """Decode a 16-bit PNG with pypng to (H, W, 3) uint16 code values (grey replicated, alpha dropped)."""
    import png  # pypng

    try:
        w, h, rows, info = png.Reader(bytes=data).asDirect()
        samples = np.vstack([np.asarray(r, dtype=np.uint16) for r in rows])
    except Exception as e:
        detail = _one_line(e, 160)
        why = "truncated" if "truncat" in detail.lower() or "EOF" in detail or "end of" in detail.lower() else "corrupt"
        raise ImageError(f"{path}: {why} PNG file ({detail})") from None
    planes = int(info.get("planes", 0))
    if samples.shape != (h, w * planes) or planes not in (1, 2, 3, 4):
        raise ImageError(f"{path}: truncated PNG file ({samples.shape[0]} of {h} rows)")
    samples = samples.reshape(h, w, planes)
    if planes <= 2:
        return np.repeat(samples[..., :1], 3, axis=2)
    return np.ascontiguousarray(samples[..., :3])


def _display_to_linear(codes: np.ndarray, maxval: int, linear: bool) -> np.ndarray:
    """Integer code values of a display image (0..maxval) as float32 linear RGB: sRGB-decoded unless ``linear``."""
    lut = np.arange(maxval + 1, dtype=np.float64) / maxval
    if not linear:
        lut = srgb_eotf(lut)
    return lut.astype(np.float32)[np.minimum(codes, maxval)]


# --------------------------------------------------------------------------
# PPM (netpbm), BMP, TGA: what student tracers write
# --------------------------------------------------------------------------

NETPBM_EXTS = (".ppm", ".pnm", ".pgm")
#: Display-referred formats: integer code values, sRGB-encoded unless declared linear.
DISPLAY_EXTS = (".png", *NETPBM_EXTS, ".bmp", ".tga")
JPEG_EXTS = (".jpg", ".jpeg", ".jpe", ".jfif")

#: Why JPEG is refused (see README.md, "Grading the course assignment").
JPEG_REASON = ("JPEG is not accepted: its lossy compression changes the mean of every 8x8 block (and halves the colour "
               "resolution) by more than the 0.3 % bias the grader penalises, so a correct render could fail; save the "
               "same image as PNG (8 or 16 bit), PPM, BMP or TGA, or as OpenEXR, PFM or HDR")


_WHITESPACE = b" \t\n\v\f\r"


def _text_raster(raster: bytes, size: int) -> bool:
    """Whether an 8-bit raster longer than its header declares is its ``size`` samples written as text and encoded
    UTF-8 (``open(path, "w").write("".join(map(chr, codes)))``, Python's default on Linux): every code of 128 or
    more two bytes, so it decodes to exactly ``size`` characters (a trailing newline aside), some beyond ASCII."""
    if not size + 1 < len(raster) <= 2 * size + 1:
        return False
    try:
        text = raster.decode("utf-8")
    except UnicodeDecodeError:
        return False
    text = text[:-1] if len(text) == size + 1 and text[-1] == "\n" else text
    return len(text) == size and max(map(ord, text)) < 256


def _late_raster(path: str, raster: bytes, size: int, *, rgb: bool, bits8: bool) -> None:
    """Refuse a binary netpbm raster that starts late: k bytes more than its header declares, the first k of them
    whitespace and the last k not (a header ended by two newlines, where netpbm allows one; a trailing newline is
    whitespace at the end instead, and is read right); one that holds twice the data or more (16-bit samples
    under an 8-bit header, or the header's size wrong); an 8-bit RGB one that holds exactly 4/3 of it (a
    program's RGBA buffer, 4 bytes a pixel, written whole: read as RGB, every pixel after the first would be read
    from the wrong bytes); and an 8-bit one written as UTF-8 text (:func:`_text_raster`: read as bytes, every
    sample after the first code of 128 or more would be read from the wrong bytes)."""
    if bits8 and _text_raster(raster, size):
        raise ImageError(f"{path}: the samples were written as text encoded UTF-8 (every code of 128 or more two "
                         "bytes: a str of chr(code) written to a file opened with 'w'): open the file with 'wb' and "
                         "write bytes (bytes(codes), or the array's tobytes())")
    rgb8 = rgb and bits8
    k = len(raster) - size
    if rgb8 and k == size // 3 > 4:  # (k <= 4 is a late raster's, below)
        raise ImageError(f"{path}: the netpbm file holds 4 bytes a pixel where its RGB header declares 3: an RGBA "
                         "buffer written whole (write each pixel's red, green and blue bytes, leaving out alpha)")
    if k >= size > 0:
        raise ImageError(f"{path}: the netpbm file holds {len(raster) / size:.3g} times the data its header declares "
                         "(a maxval of 255 or less means one byte a sample: for 16-bit samples write maxval 65535; "
                         "else check the width and height in the header)")
    if 0 < k <= 4 and all(c in _WHITESPACE for c in raster[:k]) and not all(c in _WHITESPACE for c in raster[-k:]):
        raise ImageError(f"{path}: the header is followed by {k + 1} whitespace bytes where netpbm allows one, so "
                         f"every sample would be read {k} byte{'s' * (k > 1)} late (write the samples right after the "
                         "single newline that ends the header)")


def read_netpbm(path: PathLike, linear: bool = False) -> tuple[np.ndarray, int]:
    """Read a PPM (P3 plain or P6 binary) or PGM (P2/P5), 8 or 16 bit, as ((H, W, 3) float32 RGB, bits).

    Pillow parses the header (magic, comments, size, maxval). Files with
    maxval <= 255 are decoded by Pillow; for maxval > 255 (16-bit samples,
    big-endian as netpbm specifies) the raster after Pillow's parsed header
    is read directly, because Pillow reduces such samples to 8 bits. Values
    are code / maxval, sRGB-decoded unless ``linear``.
    """
    path = os.fspath(path)
    data = _read_bytes(path)
    try:
        with _pillow_open(data, "PPM") as im:
            tile = im.tile[0] if im.tile else None
            mode, (w, h) = im.mode, im.size
            _check_pixels(path, w, h)
            args = tile.args if tile is not None else None
            maxval = int(args[1]) if isinstance(args, tuple) and len(args) > 1 else (65535 if mode == "I" else 255)
            if tile is not None and tile.codec_name != "ppm_plain":
                rgb = data[1:2] == b"6"
                _late_raster(path, data[tile.offset:], w * h * (3 if rgb else 1) * (1 + (maxval > 255)), rgb=rgb,
                             bits8=maxval <= 255)
            if maxval <= 255:
                if mode not in ("1", "L", "RGB"):
                    raise ImageError(f"{path}: unsupported netpbm pixel mode {mode}")
                im.load()  # Pillow scales samples of a maxval below 255 to 0..255
                codes = np.asarray(im if mode == "RGB" else im.convert("RGB"), dtype=np.uint8)
                return _display_to_linear(codes, 255, linear), 8
    except ImageError:
        raise
    except Image.DecompressionBombError as e:  # past Pillow's own cap, before ours is asked
        raise ImageError(f"{path}: more than the {MAX_PIXELS:,} pixels an image may have here ({_one_line(e, 120)})") from None
    except Exception as e:
        what = "not a netpbm (PPM/PGM) file" if data[:1] != b"P" else "truncated or corrupt netpbm file"
        raise ImageError(f"{path}: {what} ({_one_line(e, 160)})") from None
    planes = 3 if data[1:2] in (b"3", b"6") else 1
    n = w * h * planes
    raster = data[tile.offset:]
    if tile.codec_name == "ppm_plain":
        text = re.sub(rb"#[^\n]*", b" ", raster).split()
        if len(text) < n:
            raise ImageError(f"{path}: truncated netpbm file ({len(text)} of {n} samples)")
        try:
            codes = np.array([int(t) for t in text[:n]], dtype=np.int64)
        except ValueError:
            raise ImageError(f"{path}: corrupt netpbm file (a sample is not an integer)") from None
    else:
        if len(raster) < 2 * n:
            raise ImageError(f"{path}: truncated netpbm file ({len(raster) // 2} of {n} samples)")
        codes = np.frombuffer(raster, ">u2", count=n).astype(np.int64)
    if codes.max(initial=0) > maxval:
        raise ImageError(f"{path}: corrupt netpbm file (a sample exceeds maxval {maxval})")
    codes = codes.reshape(h, w, planes)
    if planes == 1:
        codes = np.repeat(codes, 3, axis=2)
    return _display_to_linear(codes, maxval, linear), 16


def read_bmp_tga(path: PathLike, linear: bool = False) -> np.ndarray:
    """Read a BMP or TGA (any bit depth Pillow decodes; alpha dropped) as (H, W, 3) float32 RGB, sRGB-decoded unless ``linear``."""
    path = os.fspath(path)
    kind = "BMP" if path.lower().endswith(".bmp") else "TGA"
    codes = _pillow_rgb8(path, _read_bytes(path), kind, ("1", "L", "LA", "P", "PA", "RGB", "RGBA"))
    return _display_to_linear(codes, 255, linear)


# --------------------------------------------------------------------------
# Any format
# --------------------------------------------------------------------------

_READERS = {".pfm": read_pfm, ".hdr": read_hdr, ".pic": read_hdr, ".rgbe": read_hdr}


def read_image(path: PathLike, linear_png: bool = False) -> RenderResult:
    """Read .exr, .pfm, .hdr/.pic, .png, .ppm/.pnm/.pgm, .bmp or .tga (by extension) as a RenderResult.

    EXR files keep their variance and attributes (:func:`read_exr`); the
    others give ``variance=None``, ``spp=0``, ``seed=0``, ``max_depth=0``
    and ``renderer='unknown'``. The display formats (PNG, netpbm, BMP, TGA)
    are sRGB-decoded unless ``linear_png``; their ``extra`` records
    ``file.bits`` (8 or 16) and ``file.format``. JPEG raises ImageError with
    :data:`JPEG_REASON`.
    """
    p = os.fspath(path)
    ext = Path(p).suffix.lower()
    if ext == ".exr":
        return read_exr(p)
    extra: dict = {}
    if ext == ".png":
        codes, maxval = _png_codes(p)
        rgb = _display_to_linear(codes, maxval, linear_png)
        extra = {"file.format": "PNG", "file.bits": "16" if maxval > 255 else "8"}
    elif ext in NETPBM_EXTS:
        rgb, bits = read_netpbm(p, linear=linear_png)
        extra = {"file.format": "PPM" if ext != ".pgm" else "PGM", "file.bits": str(bits)}
    elif ext in (".bmp", ".tga"):
        rgb = read_bmp_tga(p, linear=linear_png)
        extra = {"file.format": ext[1:].upper(), "file.bits": "8"}
    elif ext in JPEG_EXTS:
        raise ImageError(f"{p}: {JPEG_REASON}")
    elif ext in _READERS:
        rgb = _READERS[ext](p)
    else:
        raise ImageError(f"{p}: unknown image type {ext or '(no extension)'!r}; expected .exr, .pfm, .hdr, .pic, .png, "
                         ".ppm, .bmp or .tga")
    return RenderResult(mean=rgb, variance=None, spp=0, seed=0, max_depth=0, renderer="unknown", extra=extra)


# --------------------------------------------------------------------------
# Previews
# --------------------------------------------------------------------------


def tonemap(rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear RGB to 8-bit sRGB for viewing; (H, W, 3) uint8.

    Each value is multiplied by ``2**exposure``, clipped to [0, 1], encoded
    with the sRGB curve (:func:`srgb_oetf`) and rounded to the nearest of
    0..255 (so linear 0.5 gives 188). A pixel with any NaN channel is shown magenta
    (255, 0, 255) so a broken pixel is visible; +inf shows as 255. A
    (H, W) array is treated as grey.
    """
    a = np.asarray(rgb, dtype=np.float64)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"tonemap: expected a (height, width, 3) image, got shape {a.shape}")
    nan = np.isnan(a).any(axis=2)
    x = np.clip(np.nan_to_num(a * 2.0**exposure, nan=0.0), 0.0, 1.0)
    out = np.floor(srgb_oetf(x) * 255.0 + 0.5).astype(np.uint8)
    out[nan] = MAGENTA
    return out


def write_png(path: PathLike, rgb: np.ndarray, exposure: float = 0.0) -> None:
    """Write an 8-bit sRGB PNG preview of a linear image (:func:`tonemap`), atomically."""
    _save_png(path, tonemap(_rgb_array(path, rgb, grey=True), exposure))


def _save_png(path: PathLike, pixels: np.ndarray) -> None:
    im = Image.fromarray(pixels, "RGB")
    _atomic_write(path, lambda tmp: im.save(tmp, format="PNG"))


def side_by_side(path: PathLike, images: list[np.ndarray], labels: list[str], exposure: float = 0.0, gap: int = 4) -> None:
    """Write a PNG strip of tone-mapped images left to right, each under its label.

    Labels are drawn in pillow's default font, white on black, centred above
    their image; columns are as wide as the wider of image and label and are
    separated by ``gap`` black pixels. Images of different heights are
    top-aligned.
    """
    if not images or len(images) != len(labels):
        raise ValueError(f"side_by_side: need one label per image, got {len(images)} images and {len(labels)} labels")
    tiles = [tonemap(_rgb_array(path, im, f"image {i}", grey=True), exposure) for i, im in enumerate(images)]
    font = ImageFont.load_default()
    draw = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    boxes = [draw.textbbox((0, 0), str(s), font=font) for s in labels]
    text_h = max(b[3] for b in boxes)
    band = text_h + 2 * gap
    widths = [max(t.shape[1], b[2] - b[0] + 2 * gap) for t, b in zip(tiles, boxes)]
    total_w = sum(widths) + gap * (len(tiles) - 1)
    canvas = Image.new("RGB", (total_w, band + max(t.shape[0] for t in tiles)), (0, 0, 0))
    draw = ImageDraw.Draw(canvas)
    x = 0
    for tile, label, box, cw in zip(tiles, labels, boxes, widths):
        draw.text((x + (cw - (box[2] - box[0])) // 2 - box[0], gap), str(label), fill=(255, 255, 255), font=font)
        canvas.paste(Image.fromarray(tile, "RGB"), (x + (cw - tile.shape[1]) // 2, band))
        x += cw + gap
    _save_png(path, np.asarray(canvas))
