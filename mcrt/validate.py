"""Measuring the image comparison itself: its false-alarm rate and its power.

:func:`mcrt.stats.compare_images` promises a verdict with known error rates
both ways (shared design notes, validation.md, "Measuring the test itself").
This module measures them on the canonical scene:

False-alarm rate (:func:`false_alarm_study`)
    For each seed k, a correct mcrt render (seed k) is compared with an
    independent Mitsuba render (its own seed, ``MITSUBA_SEED_BASE + k``) at
    the same budget, or with the committed high-spp reference
    (:func:`mcrt.reference.load_reference`). Against Mitsuba every trial is
    independent (both sides are new), so the number of false alarms is
    Binomial(n, alpha') with alpha' the true rate, and its Clopper-Pearson
    interval must contain the nominal ``alpha`` (or lie below it: a
    conservative test). Against the reference the trials share the
    reference's noise, so they are independent only given the reference.
    The pooled raw tile p-values of all trials must be uniform on [0, 1]
    (Jung, Hanika and Dachsbacher 2020); their histogram and a
    Kolmogorov-Smirnov test against the uniform distribution are reported.

Power (:func:`power_study`)
    Each mutant of :data:`mcrt.mutants.MUTANTS` is rendered on ``seeds``
    seeds at the same budget and compared with the same opponent; the
    detection rate (fraction of seeds whose comparison rejects) and its
    interval are reported against the goal of :data:`POWER_GOAL`. Mutants
    below the goal are followed up: at other configurations of the default
    test suite (max depth 2, the far camera), at larger sample budgets
    (:data:`ESCALATION_SPP`, Mitsuba at the same spp), and by their effect
    size (one large-spp mcrt render with and without the mutant), which tells
    a weak test (the expected image changes, the budget is too small to see
    it) from a mutant that does not change the expected image in this scene.
    The deliberately subtle mutants (:data:`SUBTLE`, a 1 % albedo error) are
    held to the goal only at the budget found by that escalation.

Every study also evaluates the same renders with other tile sizes
(``extra_tiles``; tile 1 is the per-pixel test): the renders are the cost,
the comparisons are free, so the reports show what another tile size would
gain in power and cost in false alarms.

:func:`write_reports` writes ``false_alarms.md/.json`` and
``power.md/.json`` with the command line, versions, date, seeds and budget;
:func:`register` adds ``mcrt validate`` to a command line.

Seeds
-----
mcrt seeds are ``FALSE_ALARM_SEED_BASE + k`` (false alarms) and
``POWER_SEED_BASE + k`` (power); Mitsuba seeds are ``MITSUBA_SEED_BASE + k``
in both studies, so trial k of every study shares one Mitsuba render (each
row of a table is still a set of independent trials). Renders are pure
functions of their seeds: a study is reproducible bit for bit on one machine.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import platform
import shlex
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats as _sps

import mcrt
from mcrt.film import Progress, RenderResult
from mcrt.mutants import MUTANTS
from mcrt.scene import Scene
from mcrt.stats import binomial_interval, compare_images, floor_variance

__all__ = [
    "EXIT_FAILED",
    "EXIT_OK",
    "EXIT_UNUSABLE",
    "POWER_GOAL",
    "SCHEMA",
    "SUBTLE",
    "Budget",
    "Opponent",
    "false_alarm_bound",
    "false_alarm_study",
    "power_study",
    "register",
    "write_reports",
]

#: Schema tag of the JSON reports.
SCHEMA = "mcrt.validate/1"
#: Exit codes of ``mcrt validate``: goals met, a goal missed, unusable input.
EXIT_OK, EXIT_FAILED, EXIT_UNUSABLE = 0, 1, 2

#: Detection rate every non-subtle mutant must reach at the default budget.
POWER_GOAL = 0.95
#: Mutants that are subtle by design; held to the goal at a stated larger budget.
SUBTLE = ("albedo_1pct",)
#: Confidence level of the binomial intervals in the reports.
LEVEL = 0.95

#: Seed bases (see the module docstring).
FALSE_ALARM_SEED_BASE = 0
POWER_SEED_BASE = 10_000
MITSUBA_SEED_BASE = 500_000
EFFECT_SEEDS = (900_001, 900_002)  # mcrt seeds of the correct and mutant effect-size renders

#: Sample budgets tried, in order, for mutants below the goal at the default budget.
ESCALATION_SPP = (2048, 4096, 8192, 16384)
#: Other configurations of the default suite tried for mutants below the goal.
DEFAULT_FOLLOWUPS: tuple[dict[str, Any], ...] = ({"max_depth": 2}, {"camera": "far"})
#: Other tile sizes evaluated on the same renders.
DEFAULT_EXTRA_TILES = (1, 16, 32)
#: Samples per pixel of the effect-size renders (0: skip).
DEFAULT_EFFECT_SPP = 65536
#: Bins of the pooled p-value histogram.
P_BINS = 20


# --------------------------------------------------------------------------
# Budget and opponent
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Budget:
    """One comparison setting: what is rendered (camera, res, spp, max depth) and how it is tested.

    ``spp`` is the sample count of the image under test and, against
    Mitsuba, of the Mitsuba render too. The test is
    :func:`mcrt.stats.compare_images` with ``tile``, ``channels``,
    ``correction`` at ``alpha``.
    """

    camera: str = "near"
    res: int = 64
    spp: int = 1024
    max_depth: int = 8
    alpha: float = 0.01
    tile: int = 8
    correction: str = "holm"
    channels: str = "rgb"

    def describe(self) -> str:
        return (f"{self.camera} camera, {self.res}x{self.res}, {self.spp} spp, max depth {self.max_depth}; "
                f"{self.tile}x{self.tile} tiles, {self.channels}, {self.correction} at {self.alpha:g}")

    def n_tests(self, tile: int | None = None) -> int:
        t = tile or self.tile
        n = math.ceil(self.res / t) ** 2
        return n * (3 if self.channels == "rgb" else 1)


class Opponent:
    """The image a render under test is compared with: fresh Mitsuba renders or the committed reference.

    ``kind='mitsuba'``: trial k gets a Mitsuba render with seed
    ``MITSUBA_SEED_BASE + k`` at the budget's spp, cached in memory, so the
    false-alarm and power studies of one process share them.
    ``kind='reference'``: every trial gets the committed reference of the
    budget's (camera, res, max depth) (:func:`mcrt.reference.load_reference`).
    ``kind='reference-floor'``: the same reference, and the render under test
    takes the reference's per-sample variance where its own is lower
    (:func:`mcrt.stats.floor_variance`, the rule of ``mcrt reference verify``).
    """

    KINDS = ("mitsuba", "reference", "reference-floor")

    def __init__(self, scene: Scene, kind: str = "mitsuba", *, backend: str = "llvm", reference_dir=None):
        if kind not in self.KINDS:
            raise ValueError(f"against must be one of {', '.join(self.KINDS)}, got {kind!r}")
        self.scene, self.kind, self.backend, self.reference_dir = scene, kind, backend, reference_dir
        self._cache: dict[tuple, RenderResult] = {}
        self.seconds = 0.0  # time spent rendering opponents

    def get(self, b: Budget, k: int) -> RenderResult:
        """The opponent of trial ``k`` at budget ``b``."""
        if self.kind != "mitsuba":
            key = ("reference", b.camera, b.res, b.max_depth)
            if key not in self._cache:
                from mcrt.reference import REFERENCE_DIR, load_reference

                self._cache[key] = load_reference(self.scene, b.camera, b.res, b.max_depth,
                                                  directory=self.reference_dir or REFERENCE_DIR)
            return self._cache[key]
        key = ("mitsuba", b.camera, b.res, b.spp, b.max_depth, k)
        if key not in self._cache:
            from mcrt.mitsuba import render_mitsuba

            t0 = time.perf_counter()
            self._cache[key] = render_mitsuba(self.scene, b.camera, b.res, b.res, b.spp, MITSUBA_SEED_BASE + k,
                                              b.max_depth, backend=self.backend, progress=False)
            self.seconds += time.perf_counter() - t0
        return self._cache[key]

    def describe(self, b: Budget) -> dict[str, Any]:
        """JSON description of the opponent at budget ``b``."""
        if self.kind == "mitsuba":
            return {"kind": "mitsuba", "spp": b.spp, "seeds": f"{MITSUBA_SEED_BASE} + k (one fresh render per trial)",
                    "integrator": "path"}
        r = self.get(b, 0)
        from mcrt.reference import reference_key

        floor = self.kind == "reference-floor"
        return {"kind": self.kind, "key": reference_key(self.scene.name, b.camera, b.res, b.max_depth), "spp": int(r.spp),
                "mitsuba_version": r.extra.get("mitsuba_version", ""),
                "note": "one committed reference shared by all trials" + (
                    "; the tested render's per-sample variance floored at the reference's" if floor else "")}

    def label(self, b: Budget) -> str:
        if self.kind == "mitsuba":
            return f"independent Mitsuba renders ({b.spp} spp, seed {MITSUBA_SEED_BASE} + k)"
        d = self.describe(b)
        floor = ("; the tested render's per-sample variance raised to the reference's where lower (mcrt.stats.floor_variance)"
                 if self.kind == "reference-floor" else "")
        return f"the committed reference ({d['key']}, {d['spp']} spp){floor}"

    def compared(self, tested: RenderResult, other: RenderResult) -> RenderResult:
        """The render under test as the comparison sees it (variance-floored against ``reference-floor``)."""
        return floor_variance(tested, other) if self.kind == "reference-floor" else tested

    def forget(self, keep: Callable[[tuple], bool]) -> None:
        """Drop cached renders whose key fails ``keep`` (bounds memory between phases)."""
        self._cache = {k: v for k, v in self._cache.items() if keep(k)}


def _render_mcrt(scene: Scene, b: Budget, seed: int, mutants: Sequence[str] = (), backend: str = "llvm") -> RenderResult:
    from mcrt.tracer import render

    return render(scene, b.camera, b.spp, seed, b.max_depth, backend=backend, width=b.res, height=b.res,
                  mutants=tuple(mutants), progress=False)


# --------------------------------------------------------------------------
# Small statistics helpers
# --------------------------------------------------------------------------


def false_alarm_bound(n: int, alpha: float, level: float = 0.99) -> int:
    """Largest number of false alarms in ``n`` independent trials still consistent with level ``alpha``.

    The smallest k with P(K > k) <= 1 - level for K ~ Binomial(n, alpha): a
    correct renderer exceeds it with probability at most 1 - level. Example:
    n = 10, alpha = 0.01 gives 1 (P(K >= 2) = 0.43 %); n = 200 gives 6.
    """
    return int(_sps.binom.ppf(level, n, alpha))


def _rate_row(hits: Iterable[bool]) -> dict[str, Any]:
    hits = [bool(h) for h in hits]
    n, k = len(hits), int(sum(hits))
    lo, hi = binomial_interval(k, n, LEVEL) if n else (0.0, 1.0)
    return {"n": n, "k": k, "rate": k / n if n else float("nan"), "interval": [lo, hi]}


def _uniformity(p: np.ndarray) -> dict[str, Any]:
    """Histogram, KS test and tail fractions of p-values that should be uniform on [0, 1]."""
    p = np.asarray(p, dtype=np.float64)
    out: dict[str, Any] = {"n": int(p.size)}
    if p.size == 0:
        return out
    counts, _ = np.histogram(p, bins=P_BINS, range=(0.0, 1.0))
    ks = _sps.kstest(p, "uniform")
    out.update(
        bins=P_BINS,
        counts=[int(c) for c in counts],
        ks_statistic=float(ks.statistic),
        ks_p=float(ks.pvalue),
        below={str(q): float(np.mean(p <= q)) for q in (0.05, 0.01, 0.001, 0.0001)},
    )
    return out


def _null_max_t_quantiles(m: int, qs=(0.5, 0.9, 0.99)) -> dict[str, float]:
    """Quantiles of max |Z| over m independent standard normals: P(max < x) = (2 Phi(x) - 1)^m."""
    return {str(q): float(_sps.norm.isf((1 - q ** (1 / m)) / 2)) for q in qs}


def _trial(c, seed: int, opponent_seed: int | None) -> dict[str, Any]:
    m = c.max_abs_t
    t = abs(m.t)
    return {
        "seed": seed,
        "opponent_seed": opponent_seed,
        "rejected": not c.passed,
        "n_rejected": c.n_rejected,
        "max_abs_t": t if math.isfinite(t) else None,
        "max_abs_t_tile": [m.ty, m.tx, m.channel],
        "min_p": c.min_p,
        "min_p_adjusted": float(np.min(c.p_adjusted)),
        "global_rel_diff": [float(v) for v in c.global_rel_diff],
    }


def _median_t(trials) -> float | None:
    """Median of max |t|; an unequal deterministic tile (|t| = inf) counts as larger than any finite t."""
    v = [float("inf") if tr["max_abs_t"] is None else tr["max_abs_t"] for tr in trials]
    if not v:
        return None
    m = float(np.median(v))
    return m if math.isfinite(m) else None


def _eta(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min"


def _log(msg: str, enabled: bool) -> None:
    if enabled:
        print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------
# False alarms
# --------------------------------------------------------------------------


def _seed_list(seeds, base: int) -> list[int]:
    if isinstance(seeds, int):
        if seeds < 1:
            raise ValueError(f"need at least one seed, got {seeds}")
        return [base + k for k in range(seeds)]
    return [int(s) for s in seeds]


def false_alarm_study(
    scene: Scene,
    *,
    seeds: int | Sequence[int] = 200,
    camera: str = "near",
    res: int = 64,
    spp: int = 1024,
    max_depth: int = 8,
    alpha: float = 0.01,
    tile: int = 8,
    correction: str = "holm",
    channels: str = "rgb",
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
    seeds : int or sequence of int
        Number of trials (seeds ``FALSE_ALARM_SEED_BASE + k``), or the mcrt seeds themselves
        (trial i then uses Mitsuba seed ``MITSUBA_SEED_BASE + i``).
    against : {'mitsuba', 'reference', 'reference-floor'} or Opponent
    progress : bool
        Print a progress line (seeds done, time left) to stderr.

    Returns
    -------
    dict
        JSON-ready (see :func:`write_reports`).
    """
    b = Budget(camera, res, spp, max_depth, alpha, tile, correction, channels)
    opp = against if isinstance(against, Opponent) else Opponent(scene, against, backend=backend)
    mseeds = _seed_list(seeds, FALSE_ALARM_SEED_BASE)
    tiles = [b.tile] + [int(t) for t in extra_tiles if int(t) != b.tile]
    trials: dict[int, list[dict]] = {t: [] for t in tiles}
    pvals: dict[int, list[np.ndarray]] = {t: [] for t in tiles}
    n_det: dict[int, int] = {t: 0 for t in tiles}
    where = np.zeros((math.ceil(res / b.tile), math.ceil(res / b.tile)), dtype=np.int64)
    bar = Progress(len(mseeds), label=f"false alarms ({opp.kind})", unit="seeds", enabled=progress, every=10.0)
    t_mcrt = 0.0
    t0 = time.perf_counter()
    for i, s in enumerate(mseeds):
        other = opp.get(b, i)
        t1 = time.perf_counter()
        a = _render_mcrt(scene, b, s, backend=backend)
        t_mcrt += time.perf_counter() - t1
        a = opp.compared(a, other)
        for t in tiles:
            c = compare_images(a, other, alpha=alpha, tile=t, channels=channels, correction=correction)
            trials[t].append(_trial(c, s, MITSUBA_SEED_BASE + i if opp.kind == "mitsuba" else None))
            if t == b.tile and not c.passed:
                trials[t][-1]["summary"] = c.summary()
                where += c.rejected.any(axis=2)
            pvals[t].append(c.p_values[~c.deterministic])
            n_det[t] += int(np.count_nonzero(c.deterministic))
        bar.update(i + 1)
    total = time.perf_counter() - t0

    def block(t: int) -> dict[str, Any]:
        row = _rate_row(tr["rejected"] for tr in trials[t])
        lo, hi = row["interval"]
        m = b.n_tests(t)
        maxt = [tr["max_abs_t"] for tr in trials[t] if tr["max_abs_t"] is not None]
        row.update(
            tile=t,
            n_tests=m,
            alpha_in_interval=bool(lo <= alpha <= hi),
            goal_met=bool(lo <= alpha),
            conservative=bool(hi < alpha),
            bound_99=false_alarm_bound(row["n"], alpha, 0.99),
            acceptance_95=[int(_sps.binom.ppf(0.025, row["n"], alpha)), int(_sps.binom.isf(0.025, row["n"], alpha))],
            p_values=_uniformity(np.concatenate(pvals[t]) if pvals[t] else np.array([])),
            deterministic_tests=n_det[t],
            max_abs_t={
                "observed": {str(q): float(np.quantile(maxt, q)) for q in (0.5, 0.9, 0.99)} if maxt else {},
                "null_independent_normal": _null_max_t_quantiles(m),
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
        "seeds": {"mcrt": mseeds, "opponent": ([MITSUBA_SEED_BASE + i for i in range(len(mseeds))]
                                               if opp.kind == "mitsuba" else None)},
        "level": LEVEL,
        "primary": primary,
        "goal_met": primary["goal_met"],
        "extra_tiles": {str(t): block(t) for t in tiles[1:]},
        "rejections_by_tile": where.tolist(),
        "trials": trials[b.tile],
        "timing": {"total_s": total, "mcrt_s": t_mcrt, "opponent_s": total - t_mcrt,
                   "per_trial_s": total / len(mseeds)},
    }


# --------------------------------------------------------------------------
# Power
# --------------------------------------------------------------------------

CONTROL = "(none: correct renderer)"


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
            a = opp.compared(_render_mcrt(scene, b, s, (n,) if n else (), backend=backend), other)
            for t in tiles:
                c = compare_images(a, other, alpha=b.alpha, tile=t, channels=b.channels, correction=b.correction)
                results[n or CONTROL][t].append(_trial(c, s, MITSUBA_SEED_BASE + i if opp.kind == "mitsuba" else None))
            done += 1
            bar.update(done)
    elapsed = time.perf_counter() - t0
    rows = {}
    for name, by_tile in results.items():
        main = by_tile[tiles[0]]
        row = _rate_row(tr["rejected"] for tr in main)
        row.update(
            median_max_abs_t=_median_t(main),
            median_n_rejected=float(np.median([tr["n_rejected"] for tr in main])),
            goal_met=bool(row["rate"] >= POWER_GOAL) if name != CONTROL else bool(row["interval"][0] <= b.alpha),
            extra_tiles={str(t): dict(_rate_row(tr["rejected"] for tr in by_tile[t]), median_max_abs_t=_median_t(by_tile[t]))
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
        cache[key] = _render_mcrt(scene, eb, EFFECT_SEEDS[0], backend=backend)
    ref = cache[key]
    mut = _render_mcrt(scene, eb, EFFECT_SEEDS[1], (name,), backend=backend)
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
    camera: str = "near",
    res: int = 64,
    spp: int = 1024,
    max_depth: int = 8,
    alpha: float = 0.01,
    tile: int = 8,
    correction: str = "holm",
    channels: str = "rgb",
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

    At the default budget every mutant in ``mutants`` (default: all of
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
    b = Budget(camera, res, spp, max_depth, alpha, tile, correction, channels)
    opp = against if isinstance(against, Opponent) else Opponent(scene, against, backend=backend)
    names = list(MUTANTS) if mutants is None else list(mutants)
    for n in names:
        if n not in MUTANTS:
            raise ValueError(f"unknown mutant {n!r}; known: {', '.join(MUTANTS)}")
    pseeds = _seed_list(seeds, POWER_SEED_BASE)
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
        _log(f"follow-up {cfg}: {', '.join(below)}", progress)
        rows = _power_rows(scene, fb, [*below, None], pseeds, opp, tiles, f"follow-up {_cfg_label(cfg)}", backend, progress)
        follow_out.append({"config": dict(cfg), "label": _cfg_label(cfg), "budget": asdict(fb), "against": opp.describe(fb),
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
        _log(f"escalation to {n_spp} spp: {', '.join(pending)}", progress)
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
            _log(f"effect size of {n} at {effect_spp} spp", progress)
            effects[n] = _effect(scene, b, n, int(effect_spp), tiles, backend, cache)

    non_subtle_ok = all(main[n]["rate"] >= POWER_GOAL for n in names if n not in subtle)
    subtle_ok = all(n not in stated or stated[n]["spp"] is not None for n in names if n in subtle)
    return {
        "schema": SCHEMA,
        "study": "power",
        "budget": asdict(b),
        "against": opp.describe(b),
        "against_label": opp.label(b),
        "seeds": {"mcrt": pseeds, "opponent": ([MITSUBA_SEED_BASE + i for i in range(len(pseeds))]
                                               if opp.kind == "mitsuba" else None)},
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


def _cfg_label(cfg: dict[str, Any]) -> str:
    return ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in cfg.items())


# --------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------


def versions() -> dict[str, str]:
    """Versions of everything that decides a study's numbers."""
    import drjit
    import scipy

    out = {"mcrt": mcrt.__version__, "drjit": drjit.__version__, "numpy": np.__version__, "scipy": scipy.__version__,
           "python": platform.python_version()}
    try:
        import mitsuba

        out["mitsuba"] = mitsuba.__version__
    except ImportError:  # pragma: no cover - a dependency
        out["mitsuba"] = "not installed"
    return out


def _machine() -> dict[str, Any]:
    import os

    from mcrt.provenance import cpu_name

    cpu = cpu_name()
    return {"platform": platform.platform(), "cpu": cpu, "cores": os.cpu_count()}


def _pct(x: float | None, digits: int = 1) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:.{digits}f} %"


def _interval(iv) -> str:
    lo, hi = iv
    return f"[{100 * lo:.2f} %, {100 * hi:.2f} %]"


def _num(x, fmt=".2f") -> str:
    return "inf" if x is None else format(x, fmt)


def _header(title: str, meta: dict[str, Any], study: dict[str, Any]) -> list[str]:
    b = study["budget"]
    v = meta["versions"]
    lines = [
        f"# {title}",
        "",
        "Generated by `mcrt validate`; do not edit by hand (the interpretation is in README.md beside this file).",
        "",
        f"- Command: `{meta['command']}`",
        f"- Date: {meta['date']}",
        (f"- Versions: mcrt {v['mcrt']}, Mitsuba {v['mitsuba']}, Dr.Jit {v['drjit']}, NumPy {v['numpy']}, SciPy {v['scipy']}, "
        f"Python {v['python']}"),
        f"- Machine: {meta['machine']['cpu']} ({meta['machine']['cores']} cores), {meta['machine']['platform']}",
        f"- Scene: `{meta['scene']['path']}` (hash {meta['scene']['hash']})",
        f"- Budget: {b['camera']} camera, {b['res']}x{b['res']} pixels, {b['spp']} spp per side, max depth {b['max_depth']}",
        (f"- Test: `mcrt.stats.compare_images`: two-sample Welch test of {b['tile']}x{b['tile']} tile means "
        f"({b['channels']}), {b['correction'].title()} correction at family-wise alpha = {b['alpha']:g}"),
        f"- Image under test: mcrt (`mcrt.tracer.render`), seeds {_seed_range(study['seeds']['mcrt'])}",
        f"- Compared with: {study['against_label']}",
        f"- Intervals: Clopper-Pearson, {100 * study['level']:.0f} %",
        "",
    ]
    return lines


def _seed_range(seeds: list[int]) -> str:
    if seeds and seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}..{seeds[-1]} ({len(seeds)} seeds)"
    return ", ".join(map(str, seeds))


def _bars(counts: list[int], width: int = 40) -> list[str]:
    top = max(counts) if counts else 1
    n = len(counts)
    exp = sum(counts) / n if n else 0
    out = []
    for i, c in enumerate(counts):
        out.append(f"    [{i / n:.2f}, {(i + 1) / n:.2f})  {c:7d}  {'#' * round(width * c / max(top, 1))}")
    out.append(f"    (uniform: {exp:.0f} per bin)")
    return out


def false_alarm_markdown(fa: dict[str, Any], meta: dict[str, Any]) -> str:
    p = fa["primary"]
    b = fa["budget"]
    lines = _header("False-alarm rate of the image comparison", meta, fa)
    verdict = "met" if fa["goal_met"] else "NOT met"
    where = ("inside" if p["alpha_in_interval"] else ("above" if p["conservative"] else "below"))
    lines += [
        "## Result",
        "",
        (f"**{p['k']} false alarms in {p['n']} comparisons of correct renders: rate {_pct(p['rate'], 2)}, "
        f"95 % interval {_interval(p['interval'])}.** The nominal alpha = {b['alpha']:g} lies {where} the interval. "
        f"Goal (rate not significantly above alpha, i.e. the interval's lower end <= alpha): **{verdict}**."),
        "",
        (f"Under Binomial({p['n']}, {b['alpha']:g}) the count of false alarms lies in {p['acceptance_95'][0]}..{p['acceptance_95'][1]} "
        f"with 95 % probability and exceeds {p['bound_99']} with at most 1 % probability."),
        "",
        ("| tile | tests per comparison | false alarms | rate | 95 % interval | alpha inside | KS p of pooled p-values | "
        "max \\|t\\| median (normal null) |"),
        "|---|---|---|---|---|---|---|---|",
    ]
    for t, row in [(b["tile"], p), *((int(k), v) for k, v in fa["extra_tiles"].items())]:
        mt = row["max_abs_t"]
        obs = mt["observed"].get("0.5")
        null = mt["null_independent_normal"]["0.5"]
        tag = " (the test)" if t == b["tile"] else (" (per pixel)" if t == 1 else "")
        lines.append(
            f"| {t}{tag} | {row['n_tests']} | {row['k']} / {row['n']} | {_pct(row['rate'], 2)} | {_interval(row['interval'])} | "
            f"{'yes' if row['alpha_in_interval'] else 'no'} | {row['p_values'].get('ks_p', float('nan')):.3g} | "
            f"{_num(obs)} ({null:.2f}) |"
        )
    u = p["p_values"]
    lines += [
        "",
        f"## Pooled tile p-values ({b['tile']}x{b['tile']} tiles)",
        "",
        f"{u['n']} raw two-sided p-values (tests decided by equality of two zero-variance tiles left out: "
        f"{p['deterministic_tests']}). Under the null they are uniform on [0, 1]. Kolmogorov-Smirnov against the uniform "
        f"distribution: D = {u.get('ks_statistic', float('nan')):.4f}, p = {u.get('ks_p', float('nan')):.3g}"
        + ("" if fa["against"]["kind"] == "mitsuba" else
           " (against one shared reference the p-values of different trials are dependent, so this p is only indicative)")
        + ".",
        "",
        "| p <= | observed fraction | expected |",
        "|---|---|---|",
    ]
    for q, f in u.get("below", {}).items():
        lines.append(f"| {q} | {f:.5f} | {float(q):g} |")
    lines += ["", "Histogram:", "", *_bars(u.get("counts", [])), ""]
    q = p["max_abs_t"]
    lines += [
        "## Largest |t| per comparison",
        "",
        "| quantile | observed | max of " + f"{p['n_tests']} independent normals |",
        "|---|---|---|",
    ]
    for k in ("0.5", "0.9", "0.99"):
        lines.append(f"| {k} | {_num(q['observed'].get(k))} | {q['null_independent_normal'][k]:.2f} |")
    fails = [tr for tr in fa["trials"] if tr["rejected"]]
    lines += ["", "## The false alarms", ""]
    if not fails:
        lines.append("None.")
    else:
        lines += ["| mcrt seed | opponent seed | rejected tests | verdict |", "|---|---|---|---|"]
        for tr in fails:
            lines.append(f"| {tr['seed']} | {tr['opponent_seed'] if tr['opponent_seed'] is not None else 'reference'} | "
                         f"{tr['n_rejected']} | {tr.get('summary', '')} |")
        grid = np.array(fa["rejections_by_tile"])
        hot = [(int(v), int(y), int(x)) for (y, x), v in np.ndenumerate(grid) if v]
        hot.sort(reverse=True)
        lines += ["", "Tiles (row, column) with rejections, and in how many comparisons: "
                  + ", ".join(f"({y},{x}) {v}" for v, y, x in hot[:12])]
    tm = fa["timing"]
    lines += ["", "## Time", "",
              (f"{tm['total_s']:.0f} s in all ({tm['per_trial_s']:.2f} s per trial): mcrt {tm['mcrt_s']:.0f} s, "
              f"opponent {tm['opponent_s']:.0f} s (shared machine; timings are indicative)."), ""]
    return "\n".join(lines)


def _rate_cell(row: dict[str, Any]) -> str:
    return f"{row['k']}/{row['n']}"


def power_markdown(pw: dict[str, Any], meta: dict[str, Any]) -> str:
    b = pw["budget"]
    tiles = pw["tiles"]
    lines = _header("Power of the image comparison against the bug catalogue", meta, pw)
    goal = pw["goal"]
    lines += [
        (f"Goal: every mutant detected (the comparison rejects) on >= {100 * goal:.0f} % of seeds at this budget, "
        f"except the deliberately subtle ones ({', '.join(pw['subtle']) or 'none'}), which must reach it at a stated larger budget. "
        f"Overall: **{'met' if pw['goal_met'] else 'NOT met'}**."),
        "",
        f"## At the default budget ({b['spp']} spp, {b['tile']}x{b['tile']} tiles)",
        "",
        ("Detected = seeds on which the comparison rejected. The columns on the right evaluate the same renders with other "
        "tile sizes (tile 1: per-pixel tests); their false-alarm rates are in false_alarms.md."),
        "",
        "| mutant | detected | rate | 95 % interval | median max \\|t\\| | median rejected tests | goal | "
        + " | ".join(f"tile {t}" for t in tiles[1:]) + " |",
        "|---|---|---|---|---|---|---|" + "---|" * len(tiles[1:]),
    ]

    def row_line(name, r, subtle=False, control=False):
        if control:
            g = "(control: false alarms)"
        elif subtle:
            g = "subtle: see below"
        else:
            g = "yes" if r["goal_met"] else "**NO**"
        extra = " | ".join(_rate_cell(r["extra_tiles"][str(t)]) for t in tiles[1:])
        return (f"| {name} | {_rate_cell(r)} | {_pct(r['rate'], 0)} | {_interval(r['interval'])} | {_num(r['median_max_abs_t'], '.1f')} | "
                f"{r['median_n_rejected']:.0f} | {g} | {extra} |")

    for name, r in pw["mutants"].items():
        lines.append(row_line(f"`{name}`", r, subtle=r["subtle"]))
    lines.append(row_line(CONTROL, pw["control"], control=True))
    ctl = pw["control"]
    if ctl["interval"][0] > b["alpha"]:
        lines += ["", (f"**Warning:** the control row (correct renders) was rejected on {_rate_cell(ctl)} seeds, significantly "
                  f"more often than alpha = {b['alpha']:g}: at this budget against this opponent the test false-alarms, so the "
                  "detection rates above are inflated by false alarms and do not measure power.")]
    below = pw["below_goal"]
    lines += ["", "Below the goal at this budget: " + (", ".join(f"`{n}`" for n in below) if below else "none") + ".", ""]

    if pw["followups"]:
        lines += ["## Follow-up: other configurations of the default suite, same spp", ""]
        for f in pw["followups"]:
            fb = f["budget"]
            lines += [f"### {f['label']} ({fb['camera']} camera, max depth {fb['max_depth']}, {fb['res']}x{fb['res']}, {fb['spp']} spp)",
                      "", "| mutant | detected | rate | 95 % interval | median max \\|t\\| | "
                      + " | ".join(f"tile {t}" for t in tiles[1:]) + " |",
                      "|---|---|---|---|---|" + "---|" * len(tiles[1:])]
            for name, r in f["rows"].items():
                extra = " | ".join(_rate_cell(r["extra_tiles"][str(t)]) for t in tiles[1:])
                lines.append(f"| {name if name == CONTROL else f'`{name}`'} | {_rate_cell(r)} | {_pct(r['rate'], 0)} | "
                             f"{_interval(r['interval'])} | {_num(r['median_max_abs_t'], '.1f')} | {extra} |")
            lines.append("")
    if pw["escalation"]:
        lines += ["## Follow-up: larger budgets (default configuration, both sides at the stated spp)", "",
                  "| spp | mutant | detected | rate | 95 % interval | median max \\|t\\| | "
                  + " | ".join(f"tile {t}" for t in tiles[1:]) + " |",
                  "|---|---|---|---|---|---|" + "---|" * len(tiles[1:])]
        for lvl in pw["escalation"]:
            for name, r in lvl["rows"].items():
                extra = " | ".join(_rate_cell(r["extra_tiles"][str(t)]) for t in tiles[1:])
                lines.append(f"| {lvl['spp']} | {name if name == CONTROL else f'`{name}`'} | {_rate_cell(r)} | {_pct(r['rate'], 0)} | "
                             f"{_interval(r['interval'])} | {_num(r['median_max_abs_t'], '.1f')} | {extra} |")
        lines.append("")
    if pw["stated_budgets"]:
        lines += ["## Stated budgets", "",
                  (f"The smallest budget tried at which each mutant below the goal is detected on >= {100 * goal:.0f} % of seeds "
                  f"with {b['tile']}x{b['tile']} tiles, against {_against_words(pw['against']['kind'])}:"), ""]
        for n, s in pw["stated_budgets"].items():
            if s["spp"] is not None:
                lines.append(f"- `{n}`: {s['spp']} spp per side ({_rate_cell_from(s)}, 95 % interval {_interval(s['interval'])})")
            else:
                tried = max((lvl["spp"] for lvl in pw["escalation"]), default=b["spp"])
                other = s.get("other_tile")
                extra = ("; with " + ", ".join(f"tile {t}" + (" (per-pixel tests)" if t == 1 else "") for t in other["tiles"])
                         + f" the goal is reached at {other['spp']} spp" if other else "")
                lines.append(f"- `{n}`: not reached up to {tried} spp{extra}")
        lines.append("")
    if pw["effects"]:
        lines += ["## Effect sizes", "",
                  ("One mutant and one correct mcrt render at the stated spp, compared with each other. |t| of the most affected "
                  "test grows as sqrt(spp) when the effect dominates, so the expected |t| at the default budget is "
                  f"|t| sqrt({b['spp']} / spp). Around 4 (tile 8) to 5 (per pixel) is what the Holm threshold needs; a |t| near "
                  "noise level even at the large budget would mean the mutant does not change the expected image."), "",
                  "| mutant | spp | whole-image change (R, G, B) | " + " | ".join(
                      f"tile {t}: max \\|t\\| (at budget) | tile {t}: change there" for t in tiles) + " |",
                  "|---|---|---|" + "---|---|" * len(tiles)]
        for n, e in pw["effects"].items():
            cells = []
            for t in tiles:
                x = e["tiles"][str(t)]
                cells.append(f"{_num(x['max_abs_t'], '.1f')} ({_num(x['expected_max_abs_t_at_budget'], '.1f')})")
                cells.append(f"{100 * x['rel_diff_at_max_t']:+.2f} % at {tuple(x['at'])}")
            g = ", ".join(f"{100 * v:+.3f} %" for v in e["global_rel_diff"])
            lines.append(f"| `{n}` | {e['spp']} | {g} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## Mutants", ""]
    for n, r in pw["mutants"].items():
        lines.append(f"- `{n}`: {r['description']}")
    lines += ["", "## Time", "", f"{pw['timing']['total_s']:.0f} s in all (shared machine; timings are indicative).", ""]
    return "\n".join(lines)


def _against_words(kind: str) -> str:
    return {"mitsuba": "Mitsuba at the same spp", "reference": "the committed reference",
            "reference-floor": "the committed reference (variance floored at the reference's)"}[kind]


def _rate_cell_from(s: dict[str, Any]) -> str:
    return f"rate {_pct(s['rate'], 0)}"


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o)}")


def _clean(x):
    """Non-finite floats to None (strict JSON)."""
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def report_meta(scene: Scene, command: str) -> dict[str, Any]:
    """Provenance shared by both reports: command line, date, versions, machine, scene."""
    try:
        path = str(Path(scene.path).resolve().relative_to(Path(mcrt.__file__).resolve().parent.parent))
    except (ValueError, OSError, TypeError):
        path = str(scene.path)
    return {
        "command": command,
        "date": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "versions": versions(),
        "machine": _machine(),
        "scene": {"path": path, "hash": scene.content_hash(), "name": scene.name},
    }


def write_reports(results: dict[str, Any], out_dir: str | Path = "reports/validation") -> list[Path]:
    """Write the reports of :func:`false_alarm_study` / :func:`power_study` results.

    ``results`` holds ``meta`` (from :func:`report_meta`; without it the
    process's command line is recorded and the scene is not) and either or both
    of ``false_alarms`` and ``power``. Writes ``false_alarms.md`` and
    ``false_alarms.json``, ``power.md`` and ``power.json`` (each JSON file is
    the study's dict with the provenance under ``meta``). Returns the paths
    written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    meta = results.get("meta")
    if meta is None:  # a library call without report_meta: record what can be known here
        meta = {"command": shlex.join(sys.argv), "date": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
                "versions": versions(), "machine": _machine(), "scene": {"path": "(not recorded)", "hash": "", "name": ""}}
    written = []
    for key, stem, md in (("false_alarms", "false_alarms", false_alarm_markdown), ("power", "power", power_markdown)):
        study = results.get(key)
        if study is None:
            continue
        (out / f"{stem}.md").write_text(md(study, meta))
        (out / f"{stem}.json").write_text(json.dumps(_clean({"meta": meta, **study}), indent=1, default=_json_default) + "\n")
        written += [out / f"{stem}.md", out / f"{stem}.json"]
    return written


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------


def _int_list(text: str) -> list[int]:
    text = text.strip()
    if text in ("", "none"):
        return []
    try:
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        import argparse

        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def _followup(text: str) -> dict[str, Any]:
    """``max_depth=2`` or ``camera=far`` (several separated by commas) -> dict; ``none`` -> {}."""
    import argparse

    if text.strip() == "none":
        return {}
    out: dict[str, Any] = {}
    for part in text.split(","):
        if "=" not in part:
            raise argparse.ArgumentTypeError(f"follow-up must be KEY=VALUE (camera, res, max_depth), got {part!r}")
        k, v = (s.strip() for s in part.split("=", 1))
        k = k.replace("-", "_")
        if k not in ("camera", "res", "max_depth"):
            raise argparse.ArgumentTypeError(f"follow-up key must be camera, res or max_depth, got {k!r}")
        out[k] = v if k == "camera" else int(v)
    return out


def _command_line(args) -> str:
    """The canonical command line that reproduces a run (every option explicit)."""
    parts = ["mcrt", "validate"]
    if args.scene:
        parts += ["--scene", args.scene]
    parts += ["--seeds", str(args.seeds), "--power-seeds", str(args.power_seeds), "--spp", str(args.spp), "--res", str(args.res),
              "--camera", args.camera, "--max-depth", str(args.max_depth), "--alpha", f"{args.alpha:g}", "--tile", str(args.tile),
              "--against", args.against]
    if args.only:
        parts += ["--only", args.only]
    for m in args.mutant or ():
        parts += ["--mutant", m]
    parts += ["--extra-tiles", ",".join(map(str, args.extra_tiles)) or "none",
              "--escalate-spp", ",".join(map(str, args.escalate_spp)) or "none"]
    fus = [f for f in (args.followup if args.followup is not None else list(DEFAULT_FOLLOWUPS)) if f]
    if not fus:
        parts += ["--followup", "none"]
    for f in fus:
        parts += ["--followup", ",".join(f"{k}={v}" for k, v in f.items())]
    parts += ["--effect-spp", str(args.effect_spp), "--out", args.out]
    if args.backend != "llvm":
        parts += ["--backend", args.backend]
    return shlex.join(parts)


def register(subparsers) -> None:
    """Add ``validate`` to an argparse subparsers object (``mcrt validate``)."""
    import argparse

    p = subparsers.add_parser(
        "validate",
        help="measure the comparison's false-alarm rate and its power against the bug catalogue; write reports/validation/",
        description=(
            "Measure the image comparison (mcrt.stats.compare_images) itself. False alarms: a correct mcrt render per seed "
            "against an independent Mitsuba render (or the committed reference); the rate must not be significantly above "
            "alpha (Clopper-Pearson interval), and the pooled tile p-values should be uniform. Power: every mutant of the bug "
            f"catalogue on --power-seeds seeds at the same budget must be detected on >= {100 * POWER_GOAL:.0f} % of seeds "
            f"(the subtle {', '.join(SUBTLE)} at a larger budget found by --escalate-spp). Mutants below the goal are "
            "followed up at other configurations, larger budgets and by their effect size. Writes false_alarms.md/.json and "
            "power.md/.json with the command line and versions. Exit 0 when the goals are met, 1 when not, 2 on unusable "
            "input (e.g. --against reference without committed references)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--scene", default=None, help="scene file (default: reference/scenes/canonical.toml)")
    p.add_argument("--seeds", type=int, default=200, help="false-alarm trials (independent seeds of correct renders)")
    p.add_argument("--power-seeds", type=int, default=20, help="seeds per mutant in the power study")
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel per side (the default suite's budget)")
    p.add_argument("--res", type=int, default=64, help="square resolution N (N x N)")
    p.add_argument("--camera", default="near", help="camera name from the scene file")
    p.add_argument("--max-depth", type=int, default=8, help="longest path in segments")
    p.add_argument("--alpha", type=float, default=0.01, help="family-wise error rate of one comparison (Holm)")
    p.add_argument("--tile", type=int, default=8, help="tile size in pixels of the test under study")
    p.add_argument("--against", choices=Opponent.KINDS, default="mitsuba",
                   help="opponent: a fresh independent Mitsuba render per trial, the committed reference, or the committed "
                        "reference with the tested render's variance floored at the reference's (as `mcrt reference verify` tests)")
    p.add_argument("--only", choices=("false-alarms", "power"), default=None, help="run one study only")
    p.add_argument("--mutant", action="append", metavar="NAME", default=None,
                   help="power study for this mutant only (repeatable; default: the whole catalogue, see `mcrt mutants`)")
    p.add_argument("--extra-tiles", type=_int_list, default=list(DEFAULT_EXTRA_TILES),
                   help="other tile sizes evaluated on the same renders (comma-separated; 'none')")
    p.add_argument("--escalate-spp", type=_int_list, default=list(ESCALATION_SPP),
                   help="larger budgets tried, in order, for mutants below the goal (comma-separated; 'none')")
    p.add_argument("--followup", type=_followup, action="append", default=None, metavar="KEY=VALUE",
                   help="another configuration tried for mutants below the goal (repeatable; camera=, res=, max_depth=; "
                        "'none' for no follow-ups; default: max_depth=2 and camera=far)")
    p.add_argument("--effect-spp", type=int, default=DEFAULT_EFFECT_SPP,
                   help="spp of the effect-size renders of mutants below the goal (0: skip)")
    p.add_argument("--backend", choices=("llvm", "cuda"), default="llvm")
    p.add_argument("--out", default="reports/validation", help="report folder")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_validate)


def cmd_validate(args) -> int:
    """Run the studies selected by ``args`` and write the reports; exit code per the goals."""
    from mcrt.scene import CANONICAL, SceneError, load_scene

    progress = not args.quiet
    try:
        scene = load_scene(args.scene or CANONICAL)
        scene.camera(args.camera)
    except (SceneError, KeyError, ValueError) as e:
        print(f"mcrt validate: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    if args.seeds < 1 or args.power_seeds < 1 or args.spp < 2 or args.res < 1 or args.tile < 1 or not 0 < args.alpha < 1:
        print("mcrt validate: need --seeds, --power-seeds, --res, --tile >= 1, --spp >= 2 and 0 < --alpha < 1", file=sys.stderr)
        return EXIT_UNUSABLE
    for m in args.mutant or ():
        if m not in MUTANTS:
            print(f"mcrt validate: unknown mutant {m!r}; known: {', '.join(MUTANTS)}", file=sys.stderr)
            return EXIT_UNUSABLE
    command = _command_line(args)
    followups = [f for f in (args.followup if args.followup is not None else list(DEFAULT_FOLLOWUPS)) if f]
    common = {"camera": args.camera, "res": args.res, "spp": args.spp, "max_depth": args.max_depth, "alpha": args.alpha, "tile": args.tile,
                  "extra_tiles": args.extra_tiles, "backend": args.backend, "progress": progress}
    opp = Opponent(scene, args.against, backend=args.backend)
    results: dict[str, Any] = {"meta": report_meta(scene, command)}
    _log(f"$ {command}", progress)
    written: list[Path] = []
    try:
        if args.only in (None, "false-alarms"):
            results["false_alarms"] = false_alarm_study(scene, seeds=args.seeds, against=opp, **common)
            fa = results["false_alarms"]["primary"]
            _log(f"false alarms: {fa['k']}/{fa['n']} ({_pct(fa['rate'], 2)}, 95 % interval {_interval(fa['interval'])})", progress)
            written += write_reports({"meta": results["meta"], "false_alarms": results["false_alarms"]}, args.out)
            # Only the first power-seeds Mitsuba renders are reused by the power study.
            opp.forget(lambda k: not (k[0] == "mitsuba" and k[-1] >= args.power_seeds))
        if args.only in (None, "power"):
            results["power"] = power_study(scene, mutants=args.mutant, seeds=args.power_seeds, against=opp,
                                           escalate_spp=args.escalate_spp, followups=followups, effect_spp=args.effect_spp,
                                           **common)
    except Exception as e:
        from mcrt.reference import ReferenceUnavailable
        from mcrt.stats import StatsError

        if isinstance(e, (ReferenceUnavailable, StatsError, SceneError)):
            print(f"mcrt validate: {e}", file=sys.stderr)
            return EXIT_UNUSABLE
        raise
    if "power" in results:
        results["meta"] = dict(results["meta"], date=report_meta(scene, command)["date"])
        written += write_reports({"meta": results["meta"], "power": results["power"]}, args.out)
    for path in written:
        print(f"wrote {path}")
    ok = True
    if "false_alarms" in results:
        fa = results["false_alarms"]["primary"]
        ok &= results["false_alarms"]["goal_met"]
        print(f"false alarms: {fa['k']}/{fa['n']} = {_pct(fa['rate'], 2)}, 95 % interval {_interval(fa['interval'])}, "
              f"alpha {args.alpha:g}: {'ok' if results['false_alarms']['goal_met'] else 'TOO MANY'}")
    if "power" in results:
        pw = results["power"]
        ok &= pw["goal_met"]
        for n, r in pw["mutants"].items():
            tag = "subtle" if r["subtle"] else ("ok" if r["goal_met"] else "BELOW GOAL")
            print(f"  {n:20s} {r['k']:3d}/{r['n']:<3d} {_pct(r['rate'], 0):>6s}  {tag}")
        for n, s in pw["stated_budgets"].items():
            print(f"  {n}: " + (f"reaches the goal at {s['spp']} spp" if s["spp"] else "does not reach the goal at the budgets tried"))
        print(f"power: {'goal met' if pw['goal_met'] else 'goal NOT met'}")
    return EXIT_OK if ok else EXIT_FAILED
