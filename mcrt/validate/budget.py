"""What a study renders and how it tests: the budget, the goals, the seeds."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mcrt.scene import RenderSettings, Scene

#: Schema tag of the JSON reports.
SCHEMA = "mcrt.validate/1"

#: Detection rate every non-subtle mutant must reach at the default budget.
POWER_GOAL = 0.95
#: Mutants that are subtle by design; held to the goal at a stated larger budget.
SUBTLE = ("albedo_1pct",)
#: Confidence level of the binomial intervals in the reports.
LEVEL = 0.95

#: Seed bases: mcrt renders of trial k use ``FALSE_ALARM_SEED_BASE + k`` (false
#: alarms) or ``POWER_SEED_BASE + k`` (power); Mitsuba renders use
#: ``MITSUBA_SEED_BASE + k`` in both studies, so trial k of every study shares
#: one Mitsuba render (each row of a table is still a set of independent trials).
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
    pixel_sampler: str = "independent"  # of the image under test (mcrt.samplers; 'sobol': its default replicates)

    def n_tests(self, tile: int | None = None) -> int:
        t = tile or self.tile
        n = math.ceil(self.res / t) ** 2
        return n * (3 if self.channels == "rgb" else 1)

    def settings(self, scene: Scene) -> RenderSettings:
        """The render settings of this budget (the scene file's defaults for everything else)."""
        return scene.settings(camera=self.camera, width=self.res, height=self.res, spp=self.spp, max_depth=self.max_depth)


def seed_list(seeds: int | list[int] | tuple[int, ...], base: int) -> list[int]:
    """``seeds`` seeds from ``base`` (an int), or the given seeds themselves."""
    if isinstance(seeds, int):
        if seeds < 1:
            raise ValueError(f"need at least one seed, got {seeds}")
        return [base + k for k in range(seeds)]
    return [int(s) for s in seeds]
