"""Fireflies and convergence: error and consistency of independent renders as the budget grows."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mcrt.hardcases.cases import ALPHA, TILE
from mcrt.hardcases.catalogue import HardCase
from mcrt.hardcases.renders import render_mcrt, render_mitsuba_case

#: The firefly cases measured, and the budgets of each renderer.
CONVERGENCE_CASES = ("light_low", "light_on_wall")
CONVERGENCE_SPP = {"mcrt": (64, 256, 1024, 4096), "mitsuba": (64, 256, 1024)}
#: Independent renders per budget, their resolution, and the spp of the Mitsuba reference.
CONVERGENCE_RENDERS = 4
CONVERGENCE_RES = 64
CONVERGENCE_REF_SPP = 8192


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


def convergence(hc: HardCase, *, spps: dict[str, Sequence[int]] = CONVERGENCE_SPP, renders: int = CONVERGENCE_RENDERS,
                res: int = CONVERGENCE_RES, ref_spp: int = CONVERGENCE_REF_SPP, log=None) -> list[ConvergenceRow]:
    """How fireflies slow convergence: error and consistency of independent renders as spp grows.

    With finite per-sample variance the relative RMSE falls as spp^-1/2 and
    about 1 - alpha of the renders pass; with infinite variance (an
    area-sampled light touching a surface) a typical render is too dark where
    the light touches (the rare huge samples are missing), its estimated
    variance is too small, and renders fail at every budget: the worst tile's
    t stays large and negative as spp grows. Each render is compared with the
    reference as an independent image (no variance floor). Seeds: render k at
    n spp uses 100000 + 1000 n + k; the reference 7777.
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
