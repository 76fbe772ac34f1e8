"""Measuring the image comparison itself: its false-alarm rate and its power.

:func:`mcrt.stats.compare_images` promises a verdict with known error rates
both ways (shared design notes, validation.md, "Measuring the test itself").
This package measures them on the canonical scene:

False-alarm rate (:func:`false_alarm_study`)
    For each seed k, a correct mcrt render (seed k) is compared with an
    independent Mitsuba render (its own seed) at the same budget, or with the
    committed high-spp reference (:func:`mcrt.groundtruth.load_reference`),
    optionally with the tested render's variance floored at the reference's.
    Against Mitsuba every trial is independent, so the number of false alarms
    is Binomial(n, alpha') with alpha' the true rate, and its Clopper-Pearson
    interval must contain the nominal ``alpha`` (or lie below it: a
    conservative test). The pooled raw tile p-values of all trials must be
    uniform on [0, 1] (Jung, Hanika and Dachsbacher 2020).

Power (:func:`power_study`)
    Each mutant of :data:`mcrt.mutants.MUTANTS` is rendered on ``seeds``
    seeds at the same budget and compared with the same opponent; the
    detection rate and its interval are reported against :data:`POWER_GOAL`.
    Mutants below the goal are followed up at other configurations of the
    default test suite, at larger sample budgets, and by their effect size.
    The deliberately subtle mutants (:data:`SUBTLE`) are held to the goal
    only at the budget found by that escalation.

Every study also evaluates the same renders with other tile sizes (tile 1 is
the per-pixel test): the renders are the cost, the comparisons are free.
Renders are pure functions of their seeds (:mod:`.budget` lists the seed
bases): a study is reproducible bit for bit on one machine.

Modules: :mod:`.budget` (what is rendered and tested, goals, seeds),
:mod:`.opponent` (what a render is compared with; the variance floor),
:mod:`.rates` (binomial rates, p-value uniformity), :mod:`.false_alarms`,
:mod:`.power`, :mod:`.meta` (provenance), :mod:`.markdown` and :mod:`.data`
(the study reports, one module per format), :mod:`.readme` (the folder's
README, generated from the JSON), :mod:`.output` (writes them all),
:mod:`.cli` (``mcrt validate``).
"""

from __future__ import annotations

from mcrt.validate.budget import POWER_GOAL, SCHEMA, SUBTLE, Budget
from mcrt.validate.cli import register
from mcrt.validate.false_alarms import false_alarm_study
from mcrt.validate.meta import report_meta
from mcrt.validate.opponent import Opponent
from mcrt.validate.output import write_reports
from mcrt.validate.power import power_study
from mcrt.validate.rates import false_alarm_bound
from mcrt.validate.readme import write_readme

__all__ = [
    "POWER_GOAL",
    "SCHEMA",
    "SUBTLE",
    "Budget",
    "Opponent",
    "false_alarm_bound",
    "false_alarm_study",
    "power_study",
    "register",
    "report_meta",
    "write_readme",
    "write_reports",
]
