"""Numerical stability on hard cases: a catalogue, both renderers on each, a report.

Each hard case is a variant of the canonical room that stresses one numerical
weakness (a light in the ceiling's plane, 1/d^2 near zero distance, tangent
contacts, coplanar faces, grazing rays, extreme scales, a tiny bright light,
shared edges). :data:`CATALOGUE` names its scene (a file under
reference/scenes/hard/, or the canonical scene scaled or moved by
:meth:`mcrt.scene.Scene.scaled`), its camera and one sentence on what it
stresses.

:func:`run_case` renders a case with mcrt and with Mitsuba at equal spp,
with Mitsuba again at equal time (the spp Mitsuba traces in mcrt's render
time, JIT compilation excluded for both), and with Mitsuba at a high spp as
the reference of the error columns. It records per render the NaN/Inf count,
the negative count and the RMSE against the reference, and the verdict of
:func:`mcrt.stats.compare_images` (two-sample Welch per 8x8 tile, Holm at
0.01) between mcrt and Mitsuba at equal spp. A transformed case (scaled or
moved) is also compared with the untransformed scene's image, which it must
equal: the reference of a transformed case is rendered from the
untransformed scene, and the comparison with it floors the render's
per-sample variance at the reference's (:func:`mcrt.stats.floor_variance`).
:func:`run_all` runs the catalogue, :func:`precision_sweep` measures where
float32 breaks for each renderer (scenes moved 1e2 ... 1e5
from the origin, scaled 1e-20 ... 1e18), and :func:`write_report` writes
reports/hardcases/index.md and data.json. ``mcrt hardcases`` is the command
line (:func:`register`); it exits 1 when any case has NaN/Inf or negative
values or the renderers disagree.

Mitsuba's perspective sensor clips camera rays to [0.01, 1e4] in absolute
units (``near_clip``, ``far_clip``) by default, which cuts a scene scaled by
1e-3 (the room 0.016 wide) or 1e3 (16000 wide); :mod:`mcrt.mitsuba` scales
both clip planes with the scene. The sweep also shows what Mitsuba's
defaults would do (:func:`mitsuba_clips`).
"""

from __future__ import annotations

import contextlib
import json
import math
import platform
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

import mcrt
from mcrt.film import RenderResult
from mcrt.precision import check_precision, precision_report
from mcrt.scene import CANONICAL, SCENE_DIR, Scene, load_scene

HARD_DIR = SCENE_DIR / "hard"
REPORT_DIR = Path(__file__).resolve().parent.parent / "reports" / "hardcases"
SCHEMA = 1
EXIT_OK, EXIT_FAILED = 0, 1

#: Seeds of the four renders of a case (fixed: a report is reproducible from its command line).
SEEDS = {"mcrt": 1, "mitsuba": 2, "mitsuba_equal_time": 3, "reference": 1000}
ALPHA = 0.01
TILE = 8


# --------------------------------------------------------------------------
# The catalogue
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class HardCase:
    """One hard case: where its scene comes from, which camera sees it, what it stresses.

    ``source`` is a file name under reference/scenes/hard/ or ``canonical.toml``;
    ``factor`` and ``offset`` transform the loaded scene with
    :meth:`Scene.scaled`. ``expect`` is ``'agree'`` (both renderers finite,
    non-negative and consistent) or ``'refused'`` (beyond float32's limits:
    :func:`mcrt.precision.check_precision` must refuse it). ``known_issue``,
    when set, explains why the case fails today and what would fix it.
    """

    name: str
    sentence: str
    source: str
    camera: str
    factor: float = 1.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    intersector: str = "convex"
    expect: str = "agree"
    known_issue: str = ""

    @property
    def transformed(self) -> bool:
        return self.factor != 1.0 or any(self.offset)

    def source_path(self) -> Path:
        return CANONICAL if self.source == "canonical.toml" else HARD_DIR / self.source

    def reference_scene(self) -> Scene:
        """The untransformed scene: the reference of the error columns (same expected image)."""
        return load_scene(self.source_path())

    def scene(self) -> Scene:
        base = self.reference_scene()
        if not self.transformed:
            return base
        return replace(base.scaled(self.factor, self.offset), name=self.name, description=self.sentence)


def _file_case(name: str, camera: str, **kw) -> HardCase:
    """A case whose sentence is its scene file's ``description``."""
    return HardCase(name, load_scene(HARD_DIR / f"{name}.toml").description, f"{name}.toml", camera, **kw)



CATALOGUE: tuple[HardCase, ...] = (
    _file_case("light_on_ceiling", "near"),
    _file_case("light_on_wall", "wall"),
    _file_case("light_low", "under"),
    _file_case("sphere_tangent", "near"),
    _file_case("sphere_tiny", "zoom"),
    _file_case("tetra_on_floor", "edge_on"),
    _file_case("grazing_wall", "graze"),
    _file_case("eye_corner", "corner"),
    HardCase("scaled_1e-3", "The whole scene, cameras included, scaled by 1e-3 about the origin: the expected image is unchanged.",
             "canonical.toml", "near", factor=1e-3),
    HardCase("scaled_1e3", "The whole scene, cameras included, scaled by 1e3 about the origin: the expected image is unchanged.",
             "canonical.toml", "near", factor=1e3),
    HardCase("moved_1e3", "The scene moved by (1e3, 1e3, 1e3), within float32's limit: the expected image is unchanged.",
             "canonical.toml", "near", offset=(1e3, 1e3, 1e3)),
    HardCase("moved_1e4", "The scene moved by (1e4, 1e4, 1e4), beyond float32's limit (spawn offsets of 0.08): mcrt must refuse it.",
             "canonical.toml", "near", offset=(1e4, 1e4, 1e4), expect="refused"),
    _file_case("tiny_light", "far"),
    _file_case("shared_edges", "fan", intersector="triangles"),
)


def case(name: str) -> HardCase:
    for c in CATALOGUE:
        if c.name == name:
            return c
    raise ValueError(f"unknown hard case {name!r} (have {', '.join(c.name for c in CATALOGUE)})")


# --------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------


@contextlib.contextmanager
def mitsuba_clips(near: float, far: float) -> Iterator[None]:
    """Within the block, Mitsuba sensors built by :mod:`mcrt.mitsuba` clip camera rays to [near, far].

    :func:`mcrt.mitsuba.sensor_dict` leaves Mitsuba's absolute defaults
    (0.01, 1e4); this wraps it for the block (not thread-safe).
    """
    import mcrt.mitsuba as mm

    original = mm.sensor_dict

    def sensor_dict(*args, **kwargs):
        d = original(*args, **kwargs)
        d["near_clip"], d["far_clip"] = float(near), float(far)
        return d

    mm.sensor_dict = sensor_dict
    try:
        yield
    finally:
        mm.sensor_dict = original


def render_mcrt(hc: HardCase, scene: Scene, res: int, spp: int, seed: int, *, intersector: str | None = None,
                max_depth: int | None = None) -> RenderResult:
    """mcrt's render of ``scene`` through the case's camera (its intersector unless given)."""
    from mcrt.tracer import render

    return render(scene, hc.camera, spp, seed, max_depth, width=res, height=res, intersector=intersector or hc.intersector, progress=False)


def render_mitsuba_case(hc: HardCase, scene: Scene, res: int, spp: int, seed: int, *,
                        max_depth: int | None = None) -> RenderResult:
    """Mitsuba's render of ``scene`` through the case's camera."""
    from mcrt.mitsuba import render_mitsuba

    return render_mitsuba(scene, hc.camera, res, res, spp, seed, max_depth, progress=False)


@dataclass
class RenderStats:
    """One render of a case: budget, time, health and error against the reference."""

    renderer: str
    spp: int
    seed: int
    wall_time: float
    compile_time: float
    nonfinite: int  # NaN or Inf values in the mean and variance images
    negative: int  # negative values in the mean image
    mean: float  # image mean (NaN values ignored)
    rmse: float | None = None  # against the reference, over pixels and channels
    rel_rmse: float | None = None  # rmse / reference image mean

    @property
    def render_time(self) -> float:
        """Wall time without JIT compilation."""
        return max(self.wall_time - self.compile_time, 1e-9)


def _stats(label: str, r: RenderResult, ref: RenderResult | None) -> RenderStats:
    nonfinite = int(np.count_nonzero(~np.isfinite(r.mean)) + (np.count_nonzero(~np.isfinite(r.variance)) if r.variance is not None else 0))
    s = RenderStats(label, int(r.spp), int(r.seed), float(r.wall_time), float(r.compile_time or 0.0), nonfinite,
                    int(np.count_nonzero(r.mean < 0)), float(np.nanmean(r.mean)))
    if ref is not None:
        err = (r.mean.astype(np.float64) - ref.mean) ** 2
        s.rmse = float(np.sqrt(np.mean(err))) if np.isfinite(err).all() else math.nan
        s.rel_rmse = s.rmse / max(float(ref.mean.mean()), 1e-30)
    return s


@dataclass
class Verdict:
    """A two-sample comparison, or why none could be made (NaN/Inf in an image)."""

    passed: bool
    summary: str
    max_abs_t: float | None = None
    n_rejected: int | None = None
    global_rel_diff: list[float] | None = None


def _compare(a: RenderResult, b: RenderResult, *, reference: bool = False) -> Verdict:
    """compare_images(a, b); with ``reference``, b is a high-spp reference and a's variance is floored at b's.

    Compared with a high-spp reference without the floor, a modest render
    false-alarms on about a third of correct renders: it misses the rare
    heavy paths, so its mean and its own variance estimate come out low
    together. With the floor, on none of 200 (reports/validation/).
    """
    from mcrt.stats import StatsError, compare_images, floor_variance

    try:
        c = compare_images(floor_variance(a, b) if reference else a, b, alpha=ALPHA, tile=TILE)
    except StatsError as e:
        return Verdict(False, f"not comparable: {e}")
    return Verdict(c.passed, c.summary(), float(abs(c.max_abs_t.t)), c.n_rejected, [float(x) for x in c.global_rel_diff])


@dataclass
class CaseResult:
    name: str
    sentence: str
    source: str
    camera: str
    factor: float
    offset: tuple[float, float, float]
    intersector: str
    expect: str
    known_issue: str
    res: int
    guard: dict[str, Any]
    renders: dict[str, RenderStats] = field(default_factory=dict)
    comparisons: dict[str, Verdict] = field(default_factory=dict)
    reference_noise: float | None = None  # sqrt(mean(var_ref / ref_spp)): the error floor of the RMSE columns
    refused_by_tracer: str | None = None
    seconds: float = 0.0

    @property
    def problems(self) -> list[str]:
        """What makes this case fail (empty: it passes)."""
        out = []
        if self.expect == "refused":
            if self.guard["ok"]:
                out.append("the precision guard accepted a scene beyond float32's limits")
            return out
        for r in self.renders.values():
            if r.nonfinite:
                out.append(f"{r.renderer}: {r.nonfinite} NaN/Inf values")
            if r.negative:
                out.append(f"{r.renderer}: {r.negative} negative values")
        if not self.guard["ok"]:
            out.append("the precision guard refused it: " + str(self.guard["message"]))
        if self.refused_by_tracer:
            out.append("mcrt refused it: " + self.refused_by_tracer)
        for key in ("mcrt_vs_mitsuba", "mcrt_vs_untransformed"):
            v = self.comparisons.get(key)
            if v is not None and not v.passed:
                out.append(f"{key.replace('_', ' ')}: {v.summary.split(';')[0]}")
        return out

    @property
    def passed(self) -> bool:
        return not self.problems


def _guard(scene: Scene) -> dict[str, Any]:
    r = precision_report(scene)
    try:
        check_precision(scene)
        message = None
    except ValueError as e:
        message = str(e)
    return {"ok": message is None, "message": message, "distance": r.distance, "feature": r.feature,
            "feature_name": r.feature_name, "ratio": r.ratio, "limit": r.limit}


def run_case(hc: HardCase, *, res: int = 64, spp: int = 512, ref_spp: int = 4096, seeds: dict[str, int] = SEEDS,
             images: Path | None = None, log=None) -> CaseResult:
    """Render one case with both renderers (equal spp, equal time) and a Mitsuba reference; compare.

    Warm-up renders of 2 spp compile each kernel first, so the timed renders
    hold no JIT compilation. Mitsuba's equal-time budget is
    ``round(spp * t_mcrt / t_mitsuba)`` (at least 2), from the two timed
    renders at equal spp.
    """
    t_start = time.perf_counter()
    say = log or (lambda msg: None)
    scene = hc.scene()
    result = CaseResult(hc.name, hc.sentence, hc.source, hc.camera, hc.factor, hc.offset, hc.intersector, hc.expect,
                        hc.known_issue, res, _guard(scene))
    rendered: dict[str, RenderResult] = {}
    try:
        render_mcrt(hc, scene, res, 2, 99)  # warm-up: compile
        rendered["mcrt"] = render_mcrt(hc, scene, res, spp, seeds["mcrt"])
    except ValueError as e:  # the tracer's own precision guard
        result.refused_by_tracer = str(e)
    say(f"  {hc.name}: mcrt done")
    render_mitsuba_case(hc, scene, res, 2, 99)
    rendered["mitsuba"] = render_mitsuba_case(hc, scene, res, spp, seeds["mitsuba"])
    if "mcrt" in rendered:
        t_mcrt = max(rendered["mcrt"].wall_time - (rendered["mcrt"].compile_time or 0.0), 1e-9)
        t_mi = max(rendered["mitsuba"].wall_time - (rendered["mitsuba"].compile_time or 0.0), 1e-9)
        spp_eq = max(2, round(spp * t_mcrt / t_mi))
        rendered["mitsuba_equal_time"] = render_mitsuba_case(hc, scene, res, spp_eq, seeds["mitsuba_equal_time"])
    say(f"  {hc.name}: Mitsuba done; reference ({ref_spp} spp)")
    ref = render_mitsuba_case(hc, hc.reference_scene(), res, ref_spp, seeds["reference"])
    result.reference_noise = float(np.sqrt(np.mean(ref.variance.astype(np.float64) / ref.spp)))
    for label, r in rendered.items():
        result.renders[label] = _stats(label, r, ref)
    result.renders["reference"] = _stats("reference", ref, None)
    if "mcrt" in rendered:
        result.comparisons["mcrt_vs_mitsuba"] = _compare(rendered["mcrt"], rendered["mitsuba"])
        key = "mcrt_vs_untransformed" if hc.transformed else "mcrt_vs_reference"
        result.comparisons[key] = _compare(rendered["mcrt"], ref, reference=True)
    result.comparisons["mitsuba_vs_untransformed" if hc.transformed else "mitsuba_vs_reference"] = _compare(rendered["mitsuba"], ref, reference=True)
    if images is not None:
        from mcrt.imageio import side_by_side

        images.mkdir(parents=True, exist_ok=True)
        shown = [(k, rendered[k]) for k in ("mcrt", "mitsuba") if k in rendered] + [("reference", ref)]
        side_by_side(images / f"{hc.name}.png", [np.nan_to_num(r.mean, nan=0.0, posinf=0.0) for _, r in shown],
                     [f"{k} {r.spp}" for k, r in shown])
    result.seconds = time.perf_counter() - t_start
    return result


def run_all(cases: Sequence[HardCase] = CATALOGUE, **kw) -> list[CaseResult]:
    """:func:`run_case` on every case, in order."""
    return [run_case(hc, **kw) for hc in cases]


# --------------------------------------------------------------------------
# Where float32 breaks
# --------------------------------------------------------------------------

SWEEP_SCENES = (("canonical.toml", "near"), ("sphere_tiny.toml", "zoom"), ("tiny_light.toml", "far"))
SWEEP_OFFSETS = (1e1, 3e1, 1e2, 3e2, 1e3, 3e3, 1e4, 3e4, 1e5)
SWEEP_FACTORS = (1e-20, 1e-18, 1e-6, 1e-4, 1e-3, 1e3, 1e6, 1e17, 1e18)


@dataclass
class SweepRow:
    """One transformed scene rendered by one renderer, against that renderer's untransformed render."""

    scene: str
    camera: str
    kind: str  # 'moved' (offset (v, v, v)) or 'scaled' (factor v)
    value: float
    renderer: str  # 'mcrt', 'mitsuba', or 'mitsuba (default clips)'
    guard_ratio: float
    guard_ok: bool
    passed: bool
    nonfinite: int
    n_rejected: int | None
    max_abs_t: float | None
    mean_rel_diff: float  # (image mean - untransformed image mean) / untransformed image mean


def precision_sweep(scenes=SWEEP_SCENES, offsets=SWEEP_OFFSETS, factors=SWEEP_FACTORS, *, res: int = 32, spp: int = 1024,
                    ref_spp: int = 4096, log=None) -> list[SweepRow]:
    """Each renderer on each scene moved by (v, v, v) and scaled by v, against its own untransformed render.

    A renderer is judged against itself (an mcrt render of the scene at the
    origin with ``ref_spp``, or Mitsuba's), so a disagreement between the two
    renderers (a known issue) does not pass for a precision loss. Scaling is
    run on the first scene only, by mcrt, by Mitsuba with clip planes scaled
    with the scene, and by Mitsuba with its default clip planes.
    """
    from mcrt.mitsuba import render_mitsuba
    from mcrt.tracer import render

    say = log or (lambda msg: None)
    rows: list[SweepRow] = []

    def judge(name, cam, kind, value, renderer, scene, r, ref):
        g = precision_report(scene)
        try:
            check_precision(scene)
            ok = True
        except ValueError:
            ok = False
        if r is None:  # the renderer refused or failed on this scene
            rows.append(SweepRow(name, cam, kind, value, renderer, g.ratio, ok, False, -1, -1, float("nan"), float("nan")))
            say(f"  {name} {kind} {value:g} {renderer}: FAILED TO RENDER (guard ratio {g.ratio:.3g})")
            return
        v = _compare(r, ref)
        rel = float((np.nanmean(r.mean) - ref.mean.mean()) / ref.mean.mean())
        nonfinite = int(np.count_nonzero(~np.isfinite(r.mean)))
        rows.append(SweepRow(name, cam, kind, value, renderer, g.ratio, ok, v.passed and nonfinite == 0, nonfinite,
                             v.n_rejected, v.max_abs_t, rel))
        say(f"  {name} {kind} {value:g} {renderer}: {'ok' if rows[-1].passed else 'WRONG'} (guard ratio {g.ratio:.3g}, mean {100 * rel:+.2f} %)")

    def mcrt_render(scene, cam, n, seed):
        # The sweep measures where float32 breaks, past the guard that would refuse these scenes.
        try:
            return render(scene, cam, n, seed, None, width=res, height=res, progress=False, precision_guard=False)
        except (RuntimeError, ValueError) as e:
            say(f"  mcrt failed: {str(e).splitlines()[0]}")
            return None

    def mi_render(scene, cam, n, seed, default_clips=False):
        try:
            with mitsuba_clips(0.01, 1e4) if default_clips else contextlib.nullcontext():
                return render_mitsuba(scene, cam, res, res, n, seed, None, progress=False)
        except (RuntimeError, ValueError) as e:
            say(f"  Mitsuba failed: {str(e).splitlines()[0]}")
            return None

    for i, (source, cam) in enumerate(scenes):
        base = load_scene(CANONICAL if source == "canonical.toml" else HARD_DIR / source)
        ref_mcrt = mcrt_render(base, cam, ref_spp, 500)
        ref_mi = mi_render(base, cam, ref_spp, 501)
        for off in offsets:
            s = base.scaled(1.0, (off, off, off))
            judge(base.name, cam, "moved", off, "mcrt", s, mcrt_render(s, cam, spp, 1), ref_mcrt)
            judge(base.name, cam, "moved", off, "mitsuba", s, mi_render(s, cam, spp, 2), ref_mi)
        if i == 0:
            for f in factors:
                s = base.scaled(f)
                judge(base.name, cam, "scaled", f, "mcrt", s, mcrt_render(s, cam, spp, 1), ref_mcrt)
                judge(base.name, cam, "scaled", f, "mitsuba", s, mi_render(s, cam, spp, 2), ref_mi)
                judge(base.name, cam, "scaled", f, "mitsuba (default clips)", s, mi_render(s, cam, spp, 2, default_clips=True), ref_mi)
    return rows


def sweep_limits(rows: list[SweepRow]) -> list[dict[str, Any]]:
    """Per (scene, kind, renderer): the values that rendered right and the first that did not."""
    out = []
    keys = []
    for r in rows:
        k = (r.scene, r.camera, r.kind, r.renderer)
        if k not in keys:
            keys.append(k)
    for k in keys:
        sel = [r for r in rows if (r.scene, r.camera, r.kind, r.renderer) == k]
        good = [r.value for r in sel if r.passed]
        bad = [r.value for r in sel if not r.passed]
        if k[2] == "moved":
            first_bad = min(bad) if bad else None
            last_good = max((v for v in good if first_bad is None or v < first_bad), default=None)
            guard_max = max((r.value for r in sel if r.guard_ok), default=None)
        else:  # scaled: the widest interval of good factors around 1
            small = [v for v in sel if v.value < 1]
            large = [v for v in sel if v.value > 1]
            lo_bad = max((r.value for r in small if not r.passed), default=None)
            hi_bad = min((r.value for r in large if not r.passed), default=None)
            first_bad = (lo_bad, hi_bad)
            last_good = (min((r.value for r in small if r.passed and (lo_bad is None or r.value > lo_bad)), default=None),
                         max((r.value for r in large if r.passed and (hi_bad is None or r.value < hi_bad)), default=None))
            guard_max = None
        out.append({"scene": k[0], "camera": k[1], "kind": k[2], "renderer": k[3], "right_up_to": last_good,
                    "wrong_from": first_bad, "guard_accepts_up_to": guard_max})
    return out


# --------------------------------------------------------------------------
# Fireflies and convergence
# --------------------------------------------------------------------------

CONVERGENCE_CASES = ("light_low", "light_on_wall")
CONVERGENCE_SPP = {"mcrt": (64, 256, 1024, 4096), "mitsuba": (64, 256, 1024)}


@dataclass
class ConvergenceRow:
    """Independent renders of one case at one spp by one renderer, against a high-spp Mitsuba reference."""

    case: str
    renderer: str
    spp: int
    renders: int
    median_rel_rmse: float  # median over the renders of RMSE / reference image mean
    passed: int  # renders consistent with the reference (compare_images, alpha 0.01 Holm)
    median_worst_t: float  # median over the renders of the signed t of the tile with the largest |t|
    seconds: float  # median render time, JIT excluded


def convergence(hc: HardCase, *, spps: dict[str, Sequence[int]] = CONVERGENCE_SPP, renders: int = 4, res: int = 64,
                ref_spp: int = 8192, log=None) -> list[ConvergenceRow]:
    """How fireflies slow convergence: error and consistency of independent renders as spp grows.

    With finite per-sample variance the relative RMSE falls as spp^-1/2 and
    about 99 % of renders pass; with infinite variance (an area-sampled light
    touching a surface) a typical render is too dark where the light touches
    (the rare huge samples are missing), its estimated variance is too small,
    and renders fail at every budget: the worst tile's t stays large and
    negative as spp grows. Seeds: render k at n spp uses 100000 + 1000 n + k;
    the reference 7777.
    """
    from mcrt.stats import compare_images

    say = log or (lambda msg: None)
    scene = hc.scene()
    ref = render_mitsuba_case(hc, scene, res, ref_spp, 7777)
    ref_mean = float(ref.mean.mean())
    rows = []
    for renderer, ns in spps.items():
        for n in ns:
            errs, ts, times, ok = [], [], [], 0
            for k in range(renders):
                seed = 100000 + 1000 * n + k
                r = render_mcrt(hc, scene, res, n, seed) if renderer == "mcrt" else render_mitsuba_case(hc, scene, res, n, seed)
                errs.append(float(np.sqrt(np.mean((r.mean.astype(np.float64) - ref.mean) ** 2))) / ref_mean)
                c = compare_images(r, ref, alpha=ALPHA, tile=TILE)
                ok += c.passed
                ts.append(float(c.max_abs_t.t))
                times.append(r.wall_time - (r.compile_time or 0.0))
            rows.append(ConvergenceRow(hc.name, renderer, n, renders, float(np.median(errs)), ok, float(np.median(ts)),
                                       float(np.median(times))))
            say(f"  {hc.name} {renderer} {n} spp: rel. RMSE {rows[-1].median_rel_rmse:.3g}, {ok}/{renders} consistent, "
                f"worst t {rows[-1].median_worst_t:+.1f}")
    return rows


def convergence_slope(rows: list[ConvergenceRow], case_name: str, renderer: str) -> float:
    """Least-squares slope of log(median rel. RMSE) against log(spp): -0.5 for finite variance."""
    sel = [r for r in rows if r.case == case_name and r.renderer == renderer]
    if len(sel) < 2:
        return math.nan
    x = np.log([r.spp for r in sel])
    y = np.log([r.median_rel_rmse for r in sel])
    return float(np.polyfit(x, y, 1)[0])


# --------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------


def environment() -> dict[str, Any]:
    import drjit as dr
    import mitsuba as mi

    from mcrt.provenance import cpu_name

    cpu = cpu_name()
    return {"mcrt": mcrt.__version__, "mitsuba": mi.__version__, "drjit": dr.__version__, "numpy": np.__version__,
            "python": platform.python_version(), "cpu": cpu, "threads": dr.thread_count(),
            "date": time.strftime("%Y-%m-%d %H:%M:%S")}


def _fmt(x, spec=".3g", none="-") -> str:
    if x is None:
        return none
    if isinstance(x, float) and math.isnan(x):
        return "NaN"
    return format(x, spec)


def _case_table(results: list[CaseResult]) -> list[str]:
    lines = [
        ("| case | camera | NaN/Inf (mcrt, Mitsuba) | negative (mcrt, Mitsuba) | mcrt vs Mitsuba (equal spp) | max abs t | "
         "rel. RMSE mcrt @N | rel. RMSE Mitsuba @N | Mitsuba spp @T | rel. RMSE Mitsuba @T | mcrt s | Mitsuba s | verdict |"),
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        a, b, e = r.renders.get("mcrt"), r.renders.get("mitsuba"), r.renders.get("mitsuba_equal_time")
        v = r.comparisons.get("mcrt_vs_mitsuba")
        agree = "-" if v is None else ("agree" if v.passed else f"DIFFER ({v.n_rejected} tiles)" if v.n_rejected is not None else "not comparable")
        u = r.comparisons.get("mcrt_vs_untransformed")
        if u is not None:
            agree += "; image unchanged" if u.passed else "; IMAGE CHANGED"
        if r.expect == "refused":
            verdict = "refused by the guard (expected)" if not r.guard["ok"] else "FAIL: accepted"
        elif r.passed:
            verdict = "pass"
        else:
            verdict = "FAIL (known issue)" if r.known_issue else "FAIL"
        lines.append(
            f"| {r.name} | {r.camera} | {a.nonfinite if a else '-'}, {b.nonfinite} | {a.negative if a else '-'}, {b.negative} | {agree} | "
            f"{_fmt(v.max_abs_t if v else None, '.2f')} | {_fmt(a.rel_rmse if a else None)} | {_fmt(b.rel_rmse)} | "
            f"{e.spp if e else '-'} | {_fmt(e.rel_rmse if e else None)} | {_fmt(a.render_time if a else None, '.2f')} | "
            f"{_fmt(b.render_time, '.2f')} | {verdict} |"
        )
    return lines


def _limit_text(lim: dict[str, Any]) -> str:
    def g(v):
        return "none tested" if v is None else f"{v:g}"

    if lim["kind"] == "moved":
        text = f"right up to an offset of {g(lim['right_up_to'])}, wrong from {g(lim['wrong_from'])}"
        if lim["renderer"] == "mcrt" and lim["guard_accepts_up_to"] is not None:
            text += f"; the guard accepts up to {g(lim['guard_accepts_up_to'])}"
        return text
    (lo, hi), (lo_bad, hi_bad) = lim["right_up_to"], lim["wrong_from"]
    if lo is None and hi is None:
        return f"wrong at every tested factor (nearest to 1: {g(lo_bad)} and {g(hi_bad)})"
    return f"right for scale factors from {g(lo)} to {g(hi)}, wrong at {g(lo_bad)} and {g(hi_bad)}"


def _sweep_tables(rows: list[SweepRow]) -> list[str]:
    lines = []
    moved = [r for r in rows if r.kind == "moved"]
    if moved:
        offsets = sorted({r.value for r in moved})
        lines += [("Moved by (v, v, v): each renderer against its own render of the scene at the origin "
                   "(ok = consistent at alpha 0.01 Holm, no NaN/Inf; the % is the image mean's change; "
                   "guard = what `check_precision` says)."), "",
                  "| scene (camera) | renderer | " + " | ".join(f"{v:g}" for v in offsets) + " |",
                  "|---|---|" + "---|" * len(offsets)]
        for key in dict.fromkeys((r.scene, r.camera) for r in moved):
            for who in ("mcrt", "mitsuba", "guard"):
                cells = []
                for v in offsets:
                    sel = [r for r in moved if (r.scene, r.camera) == key and r.value == v and r.renderer == ("mcrt" if who == "guard" else who)]
                    if not sel:
                        cells.append("")
                    elif who == "guard":
                        cells.append(f"{'accept' if sel[0].guard_ok else 'refuse'} ({sel[0].guard_ratio:.2g})")
                    else:
                        cells.append(f"{'ok' if sel[0].passed else 'WRONG'} {100 * sel[0].mean_rel_diff:+.1f} %")
                lines.append(f"| {key[0]} ({key[1]}) | {who} | " + " | ".join(cells) + " |")
        lines.append("")
    scaled = [r for r in rows if r.kind == "scaled"]
    if scaled:
        factors = sorted({r.value for r in scaled})
        lines += ["Scaled by v about the origin, cameras included:", "",
                  "| scene (camera) | renderer | " + " | ".join(f"{v:g}" for v in factors) + " |",
                  "|---|---|" + "---|" * len(factors)]
        for who in ("mcrt", "mitsuba", "mitsuba (default clips)", "guard"):
            cells = []
            for v in factors:
                sel = [r for r in scaled if r.value == v and r.renderer == ("mcrt" if who == "guard" else who)]
                if not sel:
                    cells.append("")
                elif who == "guard":
                    cells.append("accept" if sel[0].guard_ok else "refuse")
                else:
                    s = sel[0]
                    if s.nonfinite < 0:
                        cells.append("failed to render")
                    else:
                        cells.append(("ok" if s.passed else "WRONG") + (f" {s.nonfinite} NaN/Inf" if s.nonfinite else f" {100 * s.mean_rel_diff:+.1f} %"))
            lines.append(f"| {scaled[0].scene} ({scaled[0].camera}) | {who} | " + " | ".join(cells) + " |")
        lines.append("")
    return lines


def _convergence_table(rows: list[ConvergenceRow]) -> list[str]:
    spps = sorted({r.spp for r in rows})
    lines = ["| case | renderer | " + " | ".join(f"{n} spp" for n in spps) + " | slope |", "|---|---|" + "---|" * (len(spps) + 1)]
    for key in dict.fromkeys((r.case, r.renderer) for r in rows):
        cells = []
        for n in spps:
            sel = [r for r in rows if (r.case, r.renderer) == key and r.spp == n]
            cells.append(f"{sel[0].median_rel_rmse:.3g} ({sel[0].passed}/{sel[0].renders} ok, t {sel[0].median_worst_t:+.1f}, "
                         f"{sel[0].seconds:.2f} s)" if sel else "")
        lines.append(f"| {key[0]} | {key[1]} | " + " | ".join(cells) + f" | {convergence_slope(rows, *key):+.2f} |")
    return lines


def write_report(results: list[CaseResult], out: Path, *, argv: Sequence[str], settings: dict[str, Any],
                 sweep: list[SweepRow] | None = None, conv: list[ConvergenceRow] | None = None) -> tuple[Path, Path]:
    """reports/hardcases/index.md (tables) and data.json (every number, schema :data:`SCHEMA`)."""
    out.mkdir(parents=True, exist_ok=True)
    env = environment()
    command = " ".join(["mcrt", "hardcases", *argv])
    data = {
        "schema": SCHEMA, "command": command, "environment": env, "settings": settings, "seeds": SEEDS,
        "alpha": ALPHA, "tile": TILE, "correction": "holm",
        "cases": [asdict(r) | {"passed": r.passed, "problems": r.problems} for r in results],
        "sweep": [asdict(r) for r in sweep] if sweep else None,
        "limits": sweep_limits(sweep) if sweep else None,
        "convergence": [asdict(r) for r in conv] if conv else None,
    }
    json_path = out / "data.json"
    json_path.write_text(json.dumps(data, indent=2, default=float) + "\n")

    res, spp, ref_spp = settings["res"], settings["spp"], settings["ref_spp"]
    lines = [
        "# Hard cases: numerical stability of mcrt and Mitsuba 3", "",
        f"Command: `{command}`  ",
        (f"mcrt {env['mcrt']}, Mitsuba {env['mitsuba']}, Dr.Jit {env['drjit']}, Python {env['python']}, "
         f"{env['threads']} threads on {env['cpu']}, {env['date']}.  "),
        (f"Seeds: mcrt {SEEDS['mcrt']}, Mitsuba {SEEDS['mitsuba']}, Mitsuba at equal time {SEEDS['mitsuba_equal_time']}, "
         f"reference {SEEDS['reference']}. Scenes: reference/scenes/hard/ (format 1) and the canonical scene transformed "
         "by `Scene.scaled(factor, offset)`."), "",
        (f"Each case is rendered at {res}x{res} by mcrt and Mitsuba (`path`, max depth 8) at N = {spp} spp each, by "
        f"Mitsuba again at equal time (@T: the spp it traces in mcrt's render time, JIT excluded), and by Mitsuba at "
        f"{ref_spp} spp as the reference of the error columns (for scaled and moved cases, from the untransformed "
        "scene: the expected image is unchanged). Agreement: `mcrt.stats.compare_images` (Welch per 8x8 tile and "
        f"channel, each side's own variance, Holm at {ALPHA}); against the reference (\"image unchanged\"), the "
        "render's per-sample variance is floored at the reference's (`mcrt.stats.floor_variance`: without it a "
        "modest render false-alarms against a high-spp reference on about a third of correct renders, "
        "reports/validation/). rel. RMSE = RMSE against the reference / the "
        "reference's image mean; the reference's own noise adds to it (data.json: reference_noise). "
        "Times are render seconds without JIT compilation."), "",
        "## Cases", "",
        "| case | what it stresses |", "|---|---|",
        *[f"| {r.name} | {r.sentence} |" for r in results], "",
        *_case_table(results), "",
    ]
    failing = [r for r in results if not r.passed]
    if failing:
        lines += ["## Failures", ""]
        for r in failing:
            lines.append(f"- **{r.name}**: " + "; ".join(r.problems))
            if r.known_issue:
                lines.append(f"  Known issue: {r.known_issue}.")
        lines.append("")
    refused = [r for r in results if r.expect == "refused"]
    for r in refused:
        lines += [f"Guard on {r.name}: {r.guard['message'] or 'accepted'}", ""]
    if sweep:
        lines += ["## Float32 limits", "", *_sweep_tables(sweep)]
        lines += ["Limits (largest value rendered right, first value rendered wrong):", ""]
        for lim in sweep_limits(sweep):
            lines.append(f"- {lim['scene']} ({lim['camera']}), {lim['kind']}, {lim['renderer']}: " + _limit_text(lim))
        lines.append("")
    if conv:
        lines += ["## Fireflies and convergence", "",
                  ("Four independent renders per budget at 64x64 against an 8192-spp Mitsuba reference of the case: median "
                   "relative RMSE, how many renders are consistent with the reference (alpha 0.01 Holm), the median signed t "
                   "of the worst tile, median render seconds, and the slope of log RMSE against log spp (-0.5 when the "
                   "per-sample variance is finite)."), "",
                  *_convergence_table(conv), ""]
    lines += ["Images (mcrt, Mitsuba, reference; tone-mapped): " + ", ".join(f"[{r.name}]({r.name}.png)" for r in results), ""]
    md_path = out / "index.md"
    md_path.write_text("\n".join(lines))
    return md_path, json_path


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------


def register(subparsers) -> None:
    """Add ``mcrt hardcases`` to the ``mcrt`` command line."""
    p = subparsers.add_parser(
        "hardcases",
        help="render the hard-case catalogue with mcrt and Mitsuba, compare, write reports/hardcases/ (exit 1 on NaN/Inf, negatives or disagreement)",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("--case", action="append", metavar="NAME", help="run only this case (repeatable; default: all; --list shows them)")
    p.add_argument("--list", action="store_true", help="list the catalogue and exit")
    p.add_argument("--spp", type=int, default=512, help="samples per pixel of each renderer at equal spp (default 512)")
    p.add_argument("--ref-spp", type=int, default=4096, help="samples per pixel of the Mitsuba reference (default 4096)")
    p.add_argument("--res", type=int, default=64, help="square resolution (default 64)")
    p.add_argument("--limits", choices=("auto", "yes", "no"), default="auto",
                   help="also measure float32's limits (moved/scaled scenes); auto: only when all cases run")
    p.add_argument("--convergence", choices=("auto", "yes", "no"), default="auto",
                   help=f"also measure convergence on the firefly cases ({', '.join(CONVERGENCE_CASES)}); auto: only when all cases run")
    p.add_argument("--out", default=str(REPORT_DIR), help="report folder (default reports/hardcases)")
    p.set_defaults(func=cmd_hardcases)


def cmd_hardcases(args) -> int:
    if args.list:
        for c in CATALOGUE:
            print(f"{c.name:18s} {c.sentence}")
        return EXIT_OK
    cases = [case(n) for n in args.case] if args.case else list(CATALOGUE)
    for name, v in (("--spp", args.spp), ("--ref-spp", args.ref_spp), ("--res", args.res)):
        if v < 2:
            raise ValueError(f"{name} must be at least 2, got {v}")

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    out = Path(args.out)
    t0 = time.perf_counter()
    results = []
    for hc in cases:
        log(f"{hc.name}: {hc.sentence}")
        r = run_case(hc, res=args.res, spp=args.spp, ref_spp=args.ref_spp, images=out, log=log)
        results.append(r)
        log(f"  {hc.name}: {'pass' if r.passed else 'FAIL: ' + '; '.join(r.problems)} ({r.seconds:.0f} s)")
    sweep = None
    if args.limits == "yes" or (args.limits == "auto" and not args.case):
        log("float32 limits: moved and scaled scenes")
        sweep = precision_sweep(log=log)
    conv = None
    if args.convergence == "yes" or (args.convergence == "auto" and not args.case):
        log("fireflies and convergence")
        conv = [row for name in CONVERGENCE_CASES for row in convergence(case(name), log=log)]
    try:
        shown_out = out.resolve().relative_to(Path.cwd())
    except ValueError:
        shown_out = out
    argv = [f"--res {args.res}", f"--spp {args.spp}", f"--ref-spp {args.ref_spp}", f"--limits {args.limits}",
            f"--convergence {args.convergence}", f"--out {shown_out}",
            *(f"--case {n}" for n in args.case or ())]
    md, js = write_report(results, out, argv=argv, settings={"res": args.res, "spp": args.spp, "ref_spp": args.ref_spp},
                          sweep=sweep, conv=conv)
    print("\n".join(_case_table(results)))
    failed = [r for r in results if not r.passed]
    print(f"{len(results) - len(failed)} of {len(results)} cases pass ({time.perf_counter() - t0:.0f} s); wrote {md} and {js}")
    for r in failed:
        print(f"FAIL {r.name}: {'; '.join(r.problems)}" + (" (known issue)" if r.known_issue else ""))
    return EXIT_FAILED if failed else EXIT_OK


def main(argv=None) -> int:
    """``python -m mcrt.hardcases``: the same as ``mcrt hardcases`` until it is wired into mcrt.cli."""
    import argparse

    ap = argparse.ArgumentParser(prog="mcrt")
    register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(["hardcases", *(sys.argv[1:] if argv is None else argv)])
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
