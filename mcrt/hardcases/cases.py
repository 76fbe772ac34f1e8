"""One hard case rendered by both renderers and judged: health of every render, agreement, error against a reference."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mcrt.film import RenderResult
from mcrt.hardcases.catalogue import HardCase
from mcrt.hardcases.renders import render_mcrt, render_mitsuba_case
from mcrt.precision import check_precision, precision_report
from mcrt.scene import Scene

#: Seeds of the four renders of a case (fixed: a report is reproducible from its command line).
SEEDS = {"mcrt": 1, "mitsuba": 2, "mitsuba_equal_time": 3, "reference": 1000}
#: Family-wise level and tile size of every comparison (Holm over tiles and channels).
ALPHA = 0.01
TILE = 8



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


def compare(a: RenderResult, b: RenderResult, *, reference: bool = False) -> Verdict:
    """The comparison of a with b; with ``reference``, b is a high-spp reference (policy ``reference-floor``).

    Compared with a high-spp reference without the floor, a modest render
    false-alarms far more often than alpha: it misses the rare heavy paths,
    so its mean and its own variance estimate come out low together
    (reports/validation/ measures both comparisons).
    """
    from mcrt.stats import StatsError, compare

    try:
        c = compare(a, b, policy="reference-floor" if reference else "independent", alpha=ALPHA, tile=TILE)
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


def guard(scene: Scene) -> dict[str, Any]:
    """What the float32 precision guard says about ``scene``: accepted or not, why, and its figures."""
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
                        hc.known_issue, res, guard(scene))
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
        result.comparisons["mcrt_vs_mitsuba"] = compare(rendered["mcrt"], rendered["mitsuba"])
        key = "mcrt_vs_untransformed" if hc.transformed else "mcrt_vs_reference"
        result.comparisons[key] = compare(rendered["mcrt"], ref, reference=True)
    result.comparisons["mitsuba_vs_untransformed" if hc.transformed else "mitsuba_vs_reference"] = compare(rendered["mitsuba"], ref, reference=True)
    if images is not None:
        from mcrt.image_files import side_by_side

        images.mkdir(parents=True, exist_ok=True)
        shown = [(k, rendered[k]) for k in ("mcrt", "mitsuba") if k in rendered] + [("reference", ref)]
        side_by_side(images / f"{hc.name}.png", [np.nan_to_num(r.mean, nan=0.0, posinf=0.0) for _, r in shown],
                     [f"{k} {r.spp}" for k, r in shown])
    result.seconds = time.perf_counter() - t_start
    return result
