"""The power study: every mutant of the bug catalogue compared with the opponent, with follow-ups."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from typing import Any

import numpy as np

from mcrt.film import Progress
from mcrt.mutants import MUTANTS
from mcrt.scene import Scene
from mcrt.stats import compare, compare_images
from mcrt.util.progress import log
from mcrt.validate.budget import (DEFAULT_EFFECT_SPP, DEFAULT_EXTRA_TILES, DEFAULT_FOLLOWUPS, EFFECT_SEEDS, ESCALATION_SPP,
                                  LEVEL, POWER_GOAL, POWER_SEED_BASE, SCHEMA, SUBTLE, Budget, seed_list)
from mcrt.validate.opponent import Opponent, render_tested
from mcrt.validate.rates import median_t, rate_row, trial

#: Row name of the correct renderer (the control) in the power tables.
CONTROL = "(none: correct renderer)"


def cfg_label(cfg: dict[str, Any]) -> str:
    """``{'max_depth': 2}`` -> ``max depth 2``."""
    return ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in cfg.items())


def _power_rows(
    scene: Scene,
    b: Budget,
    names: Sequence[str | None],
    seeds: Sequence[int],
    opp: Opponent,
    tiles: Sequence[int],
    label: str,
    backend: str,
    progress: bool,
) -> dict[str, dict[str, Any]]:
    """Detection rows for ``names`` (None = the correct renderer, the control) at budget ``b``."""
    results: dict[str, dict[int, list]] = {(n or CONTROL): {t: [] for t in tiles} for n in names}
    total = len(names) * len(seeds)
    bar = Progress(total, label=label, unit="renders", enabled=progress, every=10.0)
    done = 0
    t0 = time.perf_counter()
    for i, s in enumerate(seeds):
        other = opp.get(b, i)
        for n in names:
            a = render_tested(scene, b, s, (n,) if n else (), backend=backend)
            for t in tiles:
                c = compare(a, other, policy=opp.policy, alpha=b.alpha, tile=t, channels=b.channels, correction=b.correction)
                results[n or CONTROL][t].append(trial(c, s, opp.seed(i)))
            done += 1
            bar.update(done)
    elapsed = time.perf_counter() - t0
    rows = {}
    for name, by_tile in results.items():
        main = by_tile[tiles[0]]
        row = rate_row(tr["rejected"] for tr in main)
        row.update(
            median_max_abs_t=median_t(main),
            median_n_rejected=float(np.median([tr["n_rejected"] for tr in main])),
            goal_met=bool(row["rate"] >= POWER_GOAL) if name != CONTROL else bool(row["interval"][0] <= b.alpha),
            extra_tiles={str(t): dict(rate_row(tr["rejected"] for tr in by_tile[t]), median_max_abs_t=median_t(by_tile[t]))
                         for t in tiles[1:]},
            trials=main,
        )
        rows[name] = row
    for r in rows.values():
        r["seconds_all_rows"] = elapsed
    return rows


def _effect(scene: Scene, b: Budget, name: str, spp: int, tiles: Sequence[int], backend: str, cache: dict) -> dict[str, Any]:
    """Effect size of a mutant: mutant and correct mcrt renders at ``spp`` compared; |t| extrapolated to ``b.spp``.

    With both sides at n spp the statistic of a tile scales as sqrt(n) when
    the effect dominates, so the expected |t| at the budget is
    ``|t_n| sqrt(b.spp / n)`` (both sides at ``b.spp``). A mutant whose
    ``|t_n|`` is itself at noise level (below about 4) does not measurably
    change the expected image.
    """
    eb = replace(b, spp=spp)
    key = (eb.camera, eb.res, eb.max_depth, spp)
    if key not in cache:
        cache[key] = render_tested(scene, eb, EFFECT_SEEDS[0], backend=backend)
    ref = cache[key]
    mut = render_tested(scene, eb, EFFECT_SEEDS[1], (name,), backend=backend)
    out = {"spp": spp, "seeds": list(EFFECT_SEEDS), "tiles": {}}
    for t in tiles:
        c = compare_images(mut, ref, alpha=b.alpha, tile=t, channels=b.channels, correction=b.correction)
        m = c.max_abs_t
        tmax = abs(m.t)
        out["tiles"][str(t)] = {
            "max_abs_t": tmax if math.isfinite(tmax) else None,
            "at": [m.ty, m.tx, m.channel],
            "rel_diff_at_max_t": float(m.rel_diff),
            "n_rejected": c.n_rejected,
            "expected_max_abs_t_at_budget": tmax * math.sqrt(b.spp / spp) if math.isfinite(tmax) else None,
        }
    ga = mut.mean.astype(np.float64).reshape(-1, 3).mean(0)
    gb = ref.mean.astype(np.float64).reshape(-1, 3).mean(0)
    out["global_rel_diff"] = [float(v) for v in (ga - gb) / gb]
    return out


def power_study(
    scene: Scene,
    *,
    mutants: Sequence[str] | None = None,
    seeds: int | Sequence[int] = 20,
    budget: Budget = Budget(),
    against: str | Opponent = "mitsuba",
    extra_tiles: Sequence[int] = DEFAULT_EXTRA_TILES,
    subtle: Sequence[str] = SUBTLE,
    escalate_spp: Sequence[int] = ESCALATION_SPP,
    followups: Sequence[dict[str, Any]] = DEFAULT_FOLLOWUPS,
    effect_spp: int = DEFAULT_EFFECT_SPP,
    backend: str = "llvm",
    progress: bool = True,
) -> dict[str, Any]:
    """Measured power of :func:`mcrt.stats.compare_images` against the bug catalogue.

    At ``budget`` (default: the default suite's comparison) every mutant in ``mutants`` (default: all of
    :data:`mcrt.mutants.MUTANTS`) and the correct renderer (the control row:
    a false-alarm check on the same seeds) are rendered on ``seeds`` seeds
    (mcrt seed ``POWER_SEED_BASE + k``) and compared with the same opponent as
    the false-alarm study. Per mutant: the detection rate (seeds whose
    comparison rejects), its Clopper-Pearson interval, the median largest |t|
    and number of rejected tests, and the goal verdict (rate >=
    :data:`POWER_GOAL`; not applied to ``subtle`` mutants at this budget).

    Mutants below the goal (subtle ones included) are then followed up:

    * ``followups``: other configurations (dicts of :class:`Budget` fields,
      e.g. ``{'max_depth': 2}``) at the same spp, with their own control row;
    * ``escalate_spp``: larger budgets, in order, both sides at that spp
      (against the reference: the reference as it is), until the mutant
      reaches the goal; the first such spp is its stated budget;
    * ``effect_spp``: the effect size from one mutant and one correct mcrt
      render at that spp (see :func:`_effect`).

    Returns
    -------
    dict
        JSON-ready; ``goal_met`` is true when every non-subtle mutant reaches
        the goal at the default budget and every subtle one at some budget of
        ``escalate_spp``.
    """
    b = budget
    opp = against if isinstance(against, Opponent) else Opponent(scene, against, backend=backend)
    names = list(MUTANTS) if mutants is None else list(mutants)
    for n in names:
        if n not in MUTANTS:
            raise ValueError(f"unknown mutant {n!r}; known: {', '.join(MUTANTS)}")
    pseeds = seed_list(seeds, POWER_SEED_BASE)
    tiles = [b.tile] + [int(t) for t in extra_tiles if int(t) != b.tile]
    t_start = time.perf_counter()

    main = _power_rows(scene, b, [*names, None], pseeds, opp, tiles, "power", backend, progress)
    for n in names:
        main[n]["subtle"] = n in subtle
        main[n]["description"] = MUTANTS[n]
    below = [n for n in names if main[n]["rate"] < POWER_GOAL]

    follow_out = []
    for cfg in followups if below else ():
        fb = replace(b, **cfg)
        log(f"follow-up {cfg}: {', '.join(below)}", progress)
        rows = _power_rows(scene, fb, [*below, None], pseeds, opp, tiles, f"follow-up {cfg_label(cfg)}", backend, progress)
        follow_out.append({"config": dict(cfg), "label": cfg_label(cfg), "budget": asdict(fb), "against": opp.describe(fb),
                           "rows": rows})

    escalation = []
    pending = list(below)
    stated: dict[str, dict[str, Any]] = {n: {"spp": None} for n in below}
    for n_spp in escalate_spp:
        if not pending:
            break
        if n_spp <= b.spp:
            continue
        eb = replace(b, spp=int(n_spp))
        log(f"escalation to {n_spp} spp: {', '.join(pending)}", progress)
        rows = _power_rows(scene, eb, [*pending, None], pseeds, opp, tiles, f"escalation {n_spp} spp", backend, progress)
        escalation.append({"spp": int(n_spp), "budget": asdict(eb), "against": opp.describe(eb), "rows": rows})
        for n in list(pending):
            if rows[n]["rate"] >= POWER_GOAL:
                stated[n] = {"spp": int(n_spp), "tile": b.tile, "rate": rows[n]["rate"], "interval": rows[n]["interval"]}
                pending.remove(n)
        # Keep memory bounded: opponents of finished levels are not needed again.
        opp.forget(lambda k, level=n_spp: not (k[0] == "mitsuba" and k[3] == level))
    for n in pending:
        # Not reached at the largest budget: name the smallest (spp, tile) at which another tile size reached it.
        for lvl in escalation:
            hit = [t for t, r in lvl["rows"][n]["extra_tiles"].items() if r["rate"] >= POWER_GOAL]
            if hit:
                stated[n]["other_tile"] = {"spp": lvl["spp"], "tiles": [int(t) for t in hit]}
                break

    effects = {}
    if effect_spp and below:
        cache: dict = {}
        for n in below:
            log(f"effect size of {n} at {effect_spp} spp", progress)
            effects[n] = _effect(scene, b, n, int(effect_spp), tiles, backend, cache)

    non_subtle_ok = all(main[n]["rate"] >= POWER_GOAL for n in names if n not in subtle)
    subtle_ok = all(n not in stated or stated[n]["spp"] is not None for n in names if n in subtle)
    return {
        "schema": SCHEMA,
        "study": "power",
        "budget": asdict(b),
        "against": opp.describe(b),
        "against_label": opp.label(b),
        "seeds": {"mcrt": pseeds, "opponent": ([opp.seed(i) for i in range(len(pseeds))] if opp.kind == "mitsuba" else None)},
        "goal": POWER_GOAL,
        "level": LEVEL,
        "subtle": [n for n in names if n in subtle],
        "tiles": tiles,
        "mutants": {n: main[n] for n in names},
        "control": main[CONTROL],
        "below_goal": below,
        "followups": follow_out,
        "escalation": escalation,
        "stated_budgets": stated,
        "effects": effects,
        "goal_met": bool(non_subtle_ok and subtle_ok),
        "timing": {"total_s": time.perf_counter() - t_start},
    }
