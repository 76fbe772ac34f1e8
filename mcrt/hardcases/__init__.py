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
:func:`precision_sweep` measures where float32 breaks for each renderer
(scenes moved 1e1 ... 1e5 from the origin, scaled 1e-20 ... 1e18),
:func:`convergence` how fireflies slow convergence, and :func:`write_report`
writes reports/hardcases/index.md and data.json. ``mcrt hardcases`` is the
command line (:func:`register`); it exits 1 when any case has NaN/Inf or
negative values or the renderers disagree.

Mitsuba's perspective sensor clips camera rays to [0.01, 1e4] in absolute
units (``near_clip``, ``far_clip``) by default, which cuts a scene scaled by
1e-3 (the room 0.016 wide) or 1e3 (16000 wide); :mod:`mcrt.mitsuba_scene` scales
both clip planes with the scene. The sweep also shows what Mitsuba's
defaults would do (:func:`mitsuba_clips`).

Modules: :mod:`.catalogue`, :mod:`.renders` (both renderers through a case's
camera), :mod:`.cases` (one case rendered and judged; the variance floor),
:mod:`.sweep` (float32 limits), :mod:`.convergence`, :mod:`.markdown` and
:mod:`.data` (the report, one module per format), :mod:`.output` (writes
both), :mod:`.cli` (``mcrt hardcases``).
"""

from __future__ import annotations

from mcrt.hardcases.cases import ALPHA, SEEDS, TILE, CaseResult, RenderStats, Verdict, run_case
from mcrt.hardcases.catalogue import CATALOGUE, HARD_DIR, HardCase, case
from mcrt.hardcases.cli import register
from mcrt.hardcases.convergence import CONVERGENCE_CASES, ConvergenceRow, convergence, convergence_slope
from mcrt.hardcases.output import REPORT_DIR, write_report
from mcrt.hardcases.renders import mitsuba_clips, render_mcrt, render_mitsuba_case
from mcrt.hardcases.sweep import SweepRow, precision_sweep, sweep_limits
from mcrt.scene import CANONICAL

__all__ = [
    "ALPHA",
    "CANONICAL",
    "CATALOGUE",
    "CONVERGENCE_CASES",
    "HARD_DIR",
    "REPORT_DIR",
    "SEEDS",
    "TILE",
    "CaseResult",
    "ConvergenceRow",
    "HardCase",
    "RenderStats",
    "SweepRow",
    "Verdict",
    "case",
    "convergence",
    "convergence_slope",
    "mitsuba_clips",
    "precision_sweep",
    "register",
    "render_mcrt",
    "render_mitsuba_case",
    "run_case",
    "sweep_limits",
    "write_report",
]
