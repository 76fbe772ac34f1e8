"""Claim rules: what the feedback may say about the best explanation (:class:`mcrt.grade.candidates.ClaimRule`)."""

from __future__ import annotations

import math

from mcrt.grade.candidates import CLAIMED, INDISTINCT, NONE, Explanation, Inputs
from mcrt.grade.explain.fit import Fit

#: Share of the excess chi-square the best candidate must explain to be named.
NAMED = 0.5
#: The best candidate must also lower chi^2 by this many standard deviations of noise's chi^2 (sqrt(2 n)).
GAIN_SIGMAS = 2.0


def share_rule(e: Explanation, fit: Fit, inputs: Inputs) -> None:
    """The best candidate is claimed when it explains at least NAMED of the difference and lowers chi^2 by at
    least GAIN_SIGMAS standard deviations of noise's; a candidate with the share but not the gain is INDISTINCT."""
    best = e.best
    if best is None or best.explained < NAMED:
        e.verdict = NONE
    elif fit.chi0 - best.chi2 >= GAIN_SIGMAS * math.sqrt(2 * fit.n):
        e.verdict = CLAIMED
    else:
        e.verdict = INDISTINCT
