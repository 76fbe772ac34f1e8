"""Where float32 breaks: scenes moved ever further from the origin and scaled ever smaller and larger."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from mcrt.hardcases.cases import compare, guard
from mcrt.hardcases.catalogue import HARD_DIR
from mcrt.hardcases.renders import mitsuba_clips, settings
from mcrt.render import render
from mcrt.scene import CANONICAL, load_scene

#: Scenes (file, camera) moved away from the origin; the first is also scaled.
SWEEP_SCENES = (("canonical.toml", "near"), ("sphere_tiny.toml", "zoom"), ("tiny_light.toml", "far"))
#: Offsets v of the moved scenes (moved by (v, v, v)) and factors of the scaled one.
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
    say = log or (lambda msg: None)
    rows: list[SweepRow] = []

    def judge(name, cam, kind, value, renderer, scene, r, ref):
        g = guard(scene)
        ratio, ok = g["ratio"], g["ok"]
        if r is None:  # the renderer refused or failed on this scene
            rows.append(SweepRow(name, cam, kind, value, renderer, ratio, ok, False, -1, -1, float("nan"), float("nan")))
            say(f"  {name} {kind} {value:g} {renderer}: FAILED TO RENDER (guard ratio {ratio:.3g})")
            return
        v = compare(r, ref)
        rel = float((np.nanmean(r.mean) - ref.mean.mean()) / ref.mean.mean())
        nonfinite = int(np.count_nonzero(~np.isfinite(r.mean)))
        rows.append(SweepRow(name, cam, kind, value, renderer, ratio, ok, v.passed and nonfinite == 0, nonfinite,
                             v.n_rejected, v.max_abs_t, rel))
        say(f"  {name} {kind} {value:g} {renderer}: {'ok' if rows[-1].passed else 'WRONG'} (guard ratio {ratio:.3g}, mean {100 * rel:+.2f} %)")

    def mcrt_render(scene, cam, n, seed):
        # The sweep measures where float32 breaks, past the guard that would refuse these scenes.
        try:
            return render(scene, settings(scene, cam, res, n), renderer="mcrt", seed=seed, progress=False, precision_guard=False)
        except (RuntimeError, ValueError) as e:
            say(f"  mcrt failed: {str(e).splitlines()[0]}")
            return None

    def mi_render(scene, cam, n, seed, default_clips=False):
        try:
            with mitsuba_clips(0.01, 1e4) if default_clips else contextlib.nullcontext():
                return render(scene, settings(scene, cam, res, n), renderer="mitsuba", seed=seed, progress=False)
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
