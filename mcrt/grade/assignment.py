"""The assignment file: what students were asked to render and how it is graded.

An assignment is a TOML file (documented example:
``reference/assignments/course2023.toml``) that becomes a frozen
:class:`Assignment`. Every problem is an :class:`AssignmentError` whose
one-line message names the file and the field, for example
``course2023.toml: rubric.unbiased.alpha: must be in (0, 0.5], got 2``.

Tables
------
``[scene]``
    ``file`` (a name in ``reference/scenes/`` or a path relative to the
    assignment), ``camera``, ``width``, ``height``, ``max_depth``, ``spp``
    (what the students were asked for; the noise model's default),
    ``min_spp`` (fewer declared samples loses the noise points).
``[grading]``
    ``grade_width``/``grade_height`` (the resolution images are compared at;
    it must divide the hand-in resolution, images are box-filtered down to
    it), ``tiles`` (tile edges in grade pixels of the multi-scale bias test;
    0 is the whole image), ``reference`` (``auto``, ``mitsuba`` or
    ``mcrt``), ``reference_spp``, ``diagnosis_spp``, ``seed``,
    ``timeout`` (seconds per student), ``grade_corrected``.
``[rubric.<criterion>]``
    ``points``, ``visibility`` and the criterion's thresholds (see
    :data:`CRITERIA`). Criteria appear in results in the order of
    :data:`CRITERIA`; a criterion left out keeps its default points.
``[code]``, ``[code.checks.<name>]``
    Code mode (see :mod:`mcrt.grade.codemode`).
"""

from __future__ import annotations

import difflib
import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mcrt.scene import SCENE_DIR, Scene, SceneError, load_scene, read_capped

#: The largest assignment file read (one is a few KiB).
MAX_ASSIGNMENT_BYTES = 1 << 20

VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
REFERENCE_SOURCES = ("auto", "mitsuba", "mcrt")


class AssignmentError(ValueError):
    """An assignment file that cannot be used; the message names file and field."""


# --------------------------------------------------------------------------
# Typed description
# --------------------------------------------------------------------------

#: Criterion -> (default points, {toml key: (Thresholds field, lo, hi)}).
#: The order is the order of tests in results.json.
CRITERIA: dict[str, tuple[float, dict[str, tuple[str, float, float]]]] = {
    "readable": (5.0, {}),
    "resolution": (5.0, {}),
    "finite": (5.0, {"max_fraction": ("max_nonfinite_fraction", 0.0, 1.0)}),
    "non_negative": (5.0, {"tolerance": ("negative_tolerance", 0.0, 1.0)}),
    "linear": (5.0, {"png_gamma_loss": ("png_gamma_loss", 0.0, 1.0)}),
    "orientation": (5.0, {"margin": ("orientation_margin", 0.0, 1.0)}),
    "camera": (5.0, {}),
    "exposure": (5.0, {"max_stops": ("max_exposure_stops", 0.0, 20.0)}),
    "noise": (5.0, {"max_ratio": ("max_noise_ratio", 1.0, 1e6)}),
    "unbiased": (55.0, {
        "alpha": ("alpha", 0.0, 0.5),
        "min_effect": ("min_effect", 0.0, 1.0),
        "min_loss": ("min_loss", 0.0, 1.0),
        "full_effect": ("full_effect", 0.0, 100.0),
        "major_loss": ("major_loss", 0.0, 1.0),
        "major_coverage": ("major_coverage", 0.0, 1.0),
        "minor_loss": ("minor_loss", 0.0, 1.0),
        "minor_area": ("minor_area", 0.0, 1.0),
        "filter_loss": ("filter_loss", 0.0, 1.0),
        "min_shift": ("min_shift", 0.0, 100.0),
        "min_blur": ("min_blur", 0.0, 100.0),
        "min_correlation": ("min_correlation", 0.0, 1.0),
        "min_pixel_effect": ("min_pixel_effect", 0.0, 1.0),
    }),
    "metrics": (0.0, {}),
}

#: What each criterion checks, for feedback and documentation.
CRITERION_TITLES = {
    "readable": "File readable",
    "resolution": "Resolution",
    "finite": "No NaN or infinite values",
    "non_negative": "No negative values",
    "linear": "Linear radiance (not gamma-encoded)",
    "orientation": "Image orientation",
    "camera": "Camera",
    "exposure": "Exposure",
    "noise": "Noise level and sample count",
    "unbiased": "Unbiased (statistical test against the reference)",
    "metrics": "Error metrics (RMSE, SSIM, FLIP)",
}


@dataclass(frozen=True)
class Thresholds:
    """Numbers that decide the checks; each lives in its criterion's table."""

    max_nonfinite_fraction: float = 0.01  # finite.max_fraction: beyond it the bias test cannot run
    negative_tolerance: float = 0.0  # non_negative.tolerance: values below -tol * mean(reference) count
    orientation_margin: float = 0.05  # orientation.margin: correlation gain that proves a flip
    max_exposure_stops: float = 1.0  # exposure.max_stops: |log2 of the overall brightness ratio|
    max_noise_ratio: float = 3.0  # noise.max_ratio: measured / expected noise variance at the declared spp (a margin
    # over correct renderers' ratios: reports/grading/false_alarms)
    alpha: float = 0.01  # unbiased.alpha: family-wise error rate (Holm over tiles, scales, channels)
    min_effect: float = 0.003  # unbiased.min_effect: smaller relative biases are never penalised
    min_loss: float = 0.25  # unbiased.min_loss: share of the points lost for any penalised bias
    full_effect: float = 0.10  # unbiased.full_effect: relative bias at which a pixel counts in full
    major_loss: float = 0.75  # unbiased.major_loss: share lost at least for a major mistake (camera, a surface wrong)
    major_coverage: float = 0.5  # unbiased.major_coverage: share of a surface's pixels off by full_effect that makes it wrong
    minor_loss: float = 0.10  # unbiased.minor_loss: share lost for a mistake confined to a few pixels
    minor_area: float = 0.01  # unbiased.minor_area: share of the image below which a mistake is minor
    filter_loss: float = 0.50  # unbiased.filter_loss: share lost at least for a blurred or denoised image
    min_shift: float = 0.05  # unbiased.min_shift: grade pixels of misregistration below which it is not penalised
    min_blur: float = 0.1  # unbiased.min_blur: blur variance (grade pixels^2) below which it is not penalised
    min_correlation: float = 0.05  # unbiased.min_correlation: neighbour correlation of the noise below which it is not
    min_pixel_effect: float = 0.25  # unbiased.min_pixel_effect: relative darkening below which a pixel is not penalised
    png_gamma_loss: float = 0.0  # linear.png_gamma_loss: share lost for a PNG with a gamma of 2.2 or 2 instead of sRGB


@dataclass(frozen=True)
class Criterion:
    name: str
    points: float
    visibility: str = "visible"

    @property
    def title(self) -> str:
        return CRITERION_TITLES[self.name]


@dataclass(frozen=True)
class CodeCheck:
    """One code-mode check: ``name`` is a function of the documented interface."""

    name: str
    points: float
    visibility: str = "visible"
    params: dict[str, Any] = field(default_factory=dict)


#: Code-mode checks -> default parameters (see mcrt.grade.codemode).
CODE_CHECKS: dict[str, dict[str, Any]] = {
    "sample_cosine_hemisphere": {"samples": 200_000, "alpha": 0.01},
    "intersect_triangle": {"rays": 20_000},
    "estimate_direct": {"positions": 24, "samples": 4096, "alpha": 0.01},
    "render": {"width": 0, "height": 0, "spp": 0},  # 0: the assignment's scene.width, scene.height, scene.spp
}


@dataclass(frozen=True)
class CodeSpec:
    module: str | None  # file name students hand in; None: the only .py file
    timeout: float  # seconds of wall-clock time per check
    memory_mb: int  # address-space limit of the student's process
    checks: tuple[CodeCheck, ...]

    @property
    def max_score(self) -> float:
        return sum(c.points for c in self.checks)


@dataclass(frozen=True)
class Assignment:
    name: str
    title: str
    path: str
    scene_file: str
    camera: str
    width: int
    height: int
    max_depth: int
    spp: int
    min_spp: int
    grade_width: int
    grade_height: int
    tiles: tuple[int, ...]
    reference: str
    reference_spp: int
    diagnosis_spp: int
    seed: int
    timeout: float
    grade_corrected: bool
    rubric: tuple[Criterion, ...]
    thresholds: Thresholds
    code: CodeSpec | None = None

    @property
    def max_score(self) -> float:
        return sum(c.points for c in self.rubric)

    @property
    def factor(self) -> int:
        """Hand-in pixels per grade pixel along each axis."""
        return self.width // self.grade_width

    def criterion(self, name: str) -> Criterion:
        for c in self.rubric:
            if c.name == name:
                return c
        raise KeyError(name)

    def load_scene(self) -> Scene:
        try:
            return load_scene(self.scene_file)
        except SceneError as e:
            raise AssignmentError(f"{self.path}: scene.file: {e}") from None


# --------------------------------------------------------------------------
# Loading and validation
# --------------------------------------------------------------------------


class _Reader:
    def __init__(self, path: str):
        self.path = path

    def fail(self, where: str, problem: str) -> AssignmentError:
        return AssignmentError(f"{self.path}: {where}: {problem}")

    def table(self, d: Any, where: str, allowed: set[str], required: set[str] = frozenset()) -> dict:
        if not isinstance(d, dict):
            raise self.fail(where, f"must be a table, got {type(d).__name__}")
        for k in d:
            if k not in allowed:
                near = difflib.get_close_matches(k, sorted(allowed), n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else f" (allowed: {', '.join(sorted(allowed)) or 'none'})"
                raise self.fail(f"{where}.{k}" if where else k, f"unknown field{hint}")
        for k in sorted(required):
            if k not in d:
                raise self.fail(f"{where}.{k}" if where else k, "missing required field")
        return d

    def integer(self, v: Any, where: str, lo: int | None = None, hi: int | None = None) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(where, f"must be an integer, got {v!r}")
        if lo is not None and v < lo or hi is not None and v > hi:
            raise self.fail(where, f"must be in [{lo}, {hi if hi is not None else 'inf'}], got {v}")
        return v

    def number(self, v: Any, where: str, lo: float, hi: float, *, open_lo: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.fail(where, f"must be a number, got {v!r}")
        v = float(v)
        if not math.isfinite(v) or v < lo or v > hi or (open_lo and v == lo):
            bracket = "(" if open_lo else "["
            raise self.fail(where, f"must be in {bracket}{lo:g}, {hi:g}], got {v:g}")
        return v

    def string(self, v: Any, where: str, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(v, str) or not v:
            raise self.fail(where, f"must be a non-empty string, got {v!r}")
        if choices is not None and v not in choices:
            raise self.fail(where, f"must be one of {', '.join(choices)}, got {v!r}")
        return v

    def boolean(self, v: Any, where: str) -> bool:
        if not isinstance(v, bool):
            raise self.fail(where, f"must be true or false, got {v!r}")
        return v


def _scene_path(value: str, base: Path) -> str:
    """A scene name in reference/scenes/ or a path relative to the assignment file."""
    p = Path(value)
    if p.suffix == "" and (SCENE_DIR / f"{value}.toml").exists():
        return str(SCENE_DIR / f"{value}.toml")
    if not p.is_absolute():
        p = base / p
    return str(p)


#: The assignments of the package (reference/assignments/ of a checkout, mcrt.data.assignments when installed).
ASSIGNMENT_DIR = SCENE_DIR.parent / "assignments"


def packaged_assignments() -> list[str]:
    """The names :func:`resolve_assignment` accepts, e.g. ``course2023``."""
    return sorted(p.stem for p in ASSIGNMENT_DIR.glob("*.toml"))


def resolve_assignment(value: str | os.PathLike) -> Path:
    """An assignment file: a path as given when it exists, else a name of the package's assignments
    (``course2023`` or ``course2023.toml``), else the path as given (so that its error names it)."""
    p = Path(value)
    if p.exists() or len(p.parts) != 1:
        return p
    packaged = ASSIGNMENT_DIR / (p.name if p.suffix == ".toml" else p.name + ".toml")
    return packaged if packaged.exists() else p


def load_assignment(path: str | os.PathLike) -> Assignment:
    """Read and validate an assignment file, or one of the package's by name (see :func:`resolve_assignment`)."""
    given = path
    path = resolve_assignment(path)
    shown = str(path)
    if not os.path.lexists(path):
        raise AssignmentError(f"{given}: no such file (nor an assignment of the package: "
                              f"{', '.join(packaged_assignments())})")
    try:
        text = read_capped(path, MAX_ASSIGNMENT_BYTES, AssignmentError, "assignment file").decode("utf-8")
    except UnicodeDecodeError as e:
        raise AssignmentError(f"{shown}: cannot read ({e})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise AssignmentError(f"{shown}: not valid TOML ({e})") from None
    return assignment_from_dict(data, shown, base=path.resolve().parent)


def assignment_from_dict(data: dict, path: str = "<memory>", base: Path | None = None) -> Assignment:
    """Validate a parsed assignment (the TOML as a dict)."""
    r = _Reader(path)
    base = base or Path.cwd()
    r.table(data, "", {"format", "name", "title", "scene", "grading", "rubric", "code"}, {"scene"})
    if "format" in data and data["format"] != 1:
        raise r.fail("format", f"unsupported format {data['format']!r} (this grader reads format 1)")
    name = r.string(data.get("name", Path(path).stem), "name")
    title = r.string(data.get("title", name), "title")

    s = r.table(data["scene"], "scene", {"file", "camera", "width", "height", "max_depth", "spp", "min_spp"},
                {"camera", "width", "height"})
    scene_file = _scene_path(r.string(s.get("file", "canonical"), "scene.file"), base)
    camera = r.string(s["camera"], "scene.camera")
    width = r.integer(s["width"], "scene.width", 1, 16384)
    height = r.integer(s["height"], "scene.height", 1, 16384)
    max_depth = r.integer(s.get("max_depth", 8), "scene.max_depth", -1, 1024)
    if max_depth == 0:
        raise r.fail("scene.max_depth", "must be -1 (unbounded) or at least 1, got 0")
    spp = r.integer(s.get("spp", 100), "scene.spp", 1)
    min_spp = r.integer(s.get("min_spp", 16), "scene.min_spp", 1)

    g = r.table(data.get("grading", {}), "grading", {
        "grade_width", "grade_height", "tiles", "reference", "reference_spp", "diagnosis_spp", "seed", "timeout",
        "grade_corrected"})
    gw = r.integer(g.get("grade_width", width), "grading.grade_width", 4)
    gh = r.integer(g.get("grade_height", height), "grading.grade_height", 4)
    if width % gw or height % gh or width // gw != height // gh:
        raise r.fail("grading.grade_width", f"the grade resolution {gw}x{gh} must divide the hand-in resolution "
                     f"{width}x{height} by the same integer along both axes")
    tiles_raw = g.get("tiles", [8, 16, 32, 0])
    if not isinstance(tiles_raw, list) or not tiles_raw:
        raise r.fail("grading.tiles", f"must be a non-empty list of tile sizes (0 = whole image), got {tiles_raw!r}")
    tiles = tuple(r.integer(t, f"grading.tiles[{i}]", 0, 4096) for i, t in enumerate(tiles_raw))
    if len(set(tiles)) != len(tiles):
        raise r.fail("grading.tiles", f"repeated tile size in {list(tiles)}")
    if any(t == 1 for t in tiles):
        raise r.fail("grading.tiles", "tiles of 1 pixel leave no room for a noise estimate; use 4 or more")
    reference = r.string(g.get("reference", "auto"), "grading.reference", REFERENCE_SOURCES)
    reference_spp = r.integer(g.get("reference_spp", 4096), "grading.reference_spp", 16)
    diagnosis_spp = r.integer(g.get("diagnosis_spp", 4096), "grading.diagnosis_spp", 16)
    seed = r.integer(g.get("seed", 20231), "grading.seed", 0, 2**63 - 1)
    timeout = r.number(g.get("timeout", 120.0), "grading.timeout", 0.0, 86400.0, open_lo=True)
    grade_corrected = r.boolean(g.get("grade_corrected", True), "grading.grade_corrected")

    rub = r.table(data.get("rubric", {}), "rubric", set(CRITERIA))
    crits, th = [], {}
    for cname, (default_points, keys) in CRITERIA.items():
        t = r.table(rub.get(cname, {}), f"rubric.{cname}", {"points", "visibility", *keys})
        pts = r.number(t.get("points", default_points), f"rubric.{cname}.points", 0.0, 1e6)
        vis = r.string(t.get("visibility", "visible"), f"rubric.{cname}.visibility", VISIBILITIES)
        for k, (fname, lo, hi) in keys.items():
            if k in t:
                open_lo = fname in ("alpha", "full_effect")
                th[fname] = r.number(t[k], f"rubric.{cname}.{k}", lo, hi, open_lo=open_lo)
        crits.append(Criterion(cname, pts, vis))

    code = _code_spec(r, data["code"]) if "code" in data else None
    a = Assignment(
        name=name, title=title, path=path, scene_file=scene_file, camera=camera, width=width, height=height,
        max_depth=max_depth, spp=spp, min_spp=min_spp, grade_width=gw, grade_height=gh, tiles=tiles,
        reference=reference, reference_spp=reference_spp, diagnosis_spp=diagnosis_spp, seed=seed, timeout=timeout,
        grade_corrected=grade_corrected, rubric=tuple(crits), thresholds=Thresholds(**th), code=code,
    )
    scene = a.load_scene()
    if camera not in scene.cameras:
        raise r.fail("scene.camera", f"no camera {camera!r} in {scene.path} (have {', '.join(scene.cameras)})")
    return a


def _code_spec(r: _Reader, c: Any) -> CodeSpec:
    c = r.table(c, "code", {"module", "timeout", "memory_mb", "checks"}, {"checks"})
    module = r.string(c["module"], "code.module") if "module" in c else None
    if module is not None and (Path(module).name != module or not module.endswith(".py")):
        raise r.fail("code.module", f"must be a file name ending in .py, got {module!r}")
    timeout = r.number(c.get("timeout", 60.0), "code.timeout", 0.0, 86400.0, open_lo=True)
    memory_mb = r.integer(c.get("memory_mb", 384), "code.memory_mb", 64)
    ch = r.table(c["checks"], "code.checks", set(CODE_CHECKS))
    checks = []
    for name, t in ch.items():
        defaults = CODE_CHECKS[name]
        t = r.table(t, f"code.checks.{name}", {"points", "visibility", *defaults})
        pts = r.number(t.get("points", 10.0), f"code.checks.{name}.points", 0.0, 1e6)
        vis = r.string(t.get("visibility", "visible"), f"code.checks.{name}.visibility", VISIBILITIES)
        params = dict(defaults)
        for k, dv in defaults.items():
            if k in t:
                if isinstance(dv, int):
                    params[k] = r.integer(t[k], f"code.checks.{name}.{k}", 0 if name == "render" else 1)
                else:
                    params[k] = r.number(t[k], f"code.checks.{name}.{k}", 0.0, 1.0, open_lo=True)
        checks.append(CodeCheck(name, pts, vis, params))
    if not checks:
        raise r.fail("code.checks", "no checks listed")
    return CodeSpec(module, timeout, memory_mb, tuple(checks))
