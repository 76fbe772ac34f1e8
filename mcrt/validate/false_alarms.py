"""The false-alarm study: correct mcrt renders compared with an opponent, seed after seed."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict
from typing import Any

import numpy as np

from mcrt.film import Progress
from mcrt.scene import Scene
from mcrt.stats import compare
from mcrt.validate.budget import DEFAULT_EXTRA_TILES, FALSE_ALARM_SEED_BASE, LEVEL, SCHEMA, Budget, seed_list
from mcrt.validate.opponent import Opponent, render_tested
from mcrt.validate.rates import (binomial_acceptance, false_alarm_bound, null_max_t_quantiles, rate_row, trial,
                                 uniformity)


def false_alarm_study(
    scene: Scene,
    *,
    seeds: int | Sequence[int] = 200,
    budget: Budget = Budget(),
    against: str | Opponent = "mitsuba",
    extra_tiles: Sequence[int] = DEFAULT_EXTRA_TILES,
    backend: str = "llvm",
    progress: bool = True,
) -> dict[str, Any]:
    """Measured false-alarm rate of :func:`mcrt.stats.compare_images` on correct renders.

    Trial k compares a correct mcrt render with seed ``FALSE_ALARM_SEED_BASE
    + k`` against ``against`` (fresh Mitsuba with seed ``MITSUBA_SEED_BASE +
    k``, or the committed reference). With K false alarms in n trials the
    report gives the rate K / n, its Clopper-Pearson interval at
    :data:`LEVEL`, and the verdicts

    * ``alpha_in_interval``: the nominal level lies inside the interval;
    * ``goal_met``: the interval's lower end is at most ``alpha`` (the rate
      is not significantly above nominal; a conservative test passes);

    plus the histogram, Kolmogorov-Smirnov test and tail fractions of the
    pooled raw p-values of every non-deterministic tile test (uniform under
    the null), the distribution of the largest |t| per comparison next to
    what as many independent normal tests would give, and the tile
    positions of the rejections. ``extra_tiles`` repeats the rate and the
    uniformity check with other tile sizes on the same renders.

    Parameters
    ----------
    budget : Budget
        What is rendered and how it is tested (default: the default suite's comparison).
    seeds : int or sequence of int
        Number of trials (seeds ``FALSE_ALARM_SEED_BASE + k``), or the mcrt seeds themselves
        (trial i then uses Mitsuba seed ``MITSUBA_SEED_BASE + i``).
    against : {'mitsuba', 'reference', 'reference-floor'} or Opponent
    progress : bool
        Print a progress line (seeds done, time left) to stderr.

    Returns
    -------
    dict
        JSON-ready (see :func:`mcrt.validate.write_reports`).
    """
    b = budget
    opp = against if isinstance(against, Opponent) else Opponent(scene, against, backend=backend)
    mseeds = seed_list(seeds, FALSE_ALARM_SEED_BASE)
    tiles = [b.tile] + [int(t) for t in extra_tiles if int(t) != b.tile]
    trials: dict[int, list[dict]] = {t: [] for t in tiles}
    pvals: dict[int, list[np.ndarray]] = {t: [] for t in tiles}
    n_det: dict[int, int] = {t: 0 for t in tiles}
    where = np.zeros((math.ceil(b.res / b.tile), math.ceil(b.res / b.tile)), dtype=np.int64)
    bar = Progress(len(mseeds), label=f"false alarms ({opp.kind})", unit="seeds", enabled=progress, every=10.0)
    t_mcrt = 0.0
    t0 = time.perf_counter()
    for i, s in enumerate(mseeds):
        other = opp.get(b, i)
        t1 = time.perf_counter()
        a = render_tested(scene, b, s, backend=backend)
        t_mcrt += time.perf_counter() - t1
        for t in tiles:
            c = compare(a, other, policy=opp.policy, alpha=b.alpha, tile=t, channels=b.channels, correction=b.correction)
            trials[t].append(trial(c, s, opp.seed(i)))
            if t == b.tile and not c.passed:
                trials[t][-1]["summary"] = c.summary()
                where += c.rejected.any(axis=2)
            pvals[t].append(c.p_values[~c.deterministic])
            n_det[t] += int(np.count_nonzero(c.deterministic))
        bar.update(i + 1)
    total = time.perf_counter() - t0

    def block(t: int) -> dict[str, Any]:
        row = rate_row(tr["rejected"] for tr in trials[t])
        lo, hi = row["interval"]
        m = b.n_tests(t)
        maxt = [tr["max_abs_t"] for tr in trials[t] if tr["max_abs_t"] is not None]
        row.update(
            tile=t,
            n_tests=m,
            alpha_in_interval=bool(lo <= b.alpha <= hi),
            goal_met=bool(lo <= b.alpha),
            conservative=bool(hi < b.alpha),
            bound_99=false_alarm_bound(row["n"], b.alpha, 0.99),
            acceptance_95=binomial_acceptance(row["n"], b.alpha),
            p_values=uniformity(np.concatenate(pvals[t]) if pvals[t] else np.array([])),
            deterministic_tests=n_det[t],
            max_abs_t={
                "observed": {str(q): float(np.quantile(maxt, q)) for q in (0.5, 0.9, 0.99)} if maxt else {},
                "null_independent_normal": null_max_t_quantiles(m),
            },
        )
        return row

    primary = block(b.tile)
    return {
        "schema": SCHEMA,
        "study": "false_alarms",
        "budget": asdict(b),
        "against": opp.describe(b),
        "against_label": opp.label(b),
        "seeds": {"mcrt": mseeds, "opponent": ([opp.seed(i) for i in range(len(mseeds))] if opp.kind == "mitsuba" else None)},
        "level": LEVEL,
        "primary": primary,
        "goal_met": primary["goal_met"],
        "extra_tiles": {str(t): block(t) for t in tiles[1:]},
        "rejections_by_tile": where.tolist(),
        "trials": trials[b.tile],
        "timing": {"total_s": total, "mcrt_s": t_mcrt, "opponent_s": total - t_mcrt,
                   "per_trial_s": total / len(mseeds)},
    }
