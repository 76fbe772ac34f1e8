"""The explanation stage: every family's candidates, ranked by the share of the difference each explains.

See :mod:`mcrt.grade.explain` for the model and :mod:`mcrt.grade.candidates`
for the contract between the engine, the families and the claim rules.
"""

from __future__ import annotations

import math
import time

import numpy as np

from mcrt.grade.candidates import TIE, Candidate, ClaimRule, Explanation, Family, Inputs
from mcrt.grade.explain.claim import share_rule
from mcrt.grade.explain.families import FAMILIES
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import explanation_words


def explain(S: np.ndarray, R: np.ndarray, V: np.ndarray, mask: np.ndarray, inputs: Inputs, *,
            families: tuple[Family, ...] | None = None, claim: ClaimRule | None = None, tile: int = 8) -> Explanation:
    """Fit every family of mistakes to the image S (see :mod:`mcrt.grade.explain`).

    ``V`` is the per-pixel noise variance of S - R (the student's and the
    reference's), ``mask`` the pixels to use; ``inputs`` holds the basis,
    the catalogue (its bugs are candidates among the families) and the
    region words. ``families`` defaults to :data:`mcrt.grade.explain.families.FAMILIES`,
    ``claim`` to :func:`mcrt.grade.explain.claim.share_rule`; ``tile`` is the
    edge of the tiles of the tile level of chi^2 (:class:`Fit`). The words
    (``sentence``, ``headline``) come from :func:`mcrt.grade.feedback.explanation_words`.
    """
    t0 = time.perf_counter()
    S, R, V = (np.asarray(x, np.float64) for x in (S, R, V))
    ok = mask[..., None] & np.isfinite(S) & np.isfinite(V) & np.isfinite(R)
    ok = np.broadcast_to(ok, S.shape)
    basis = inputs.basis
    W = basis.var.astype(np.float64) / basis.spp  # a variation minus the base, common random numbers
    fit = Fit(S, R, V, ok, W, tile)
    cands: list[Candidate] = []
    for family in (FAMILIES if families is None else families):
        cands += family(fit, inputs)
    cands = rank(cands, fit)
    for c in cands[:5]:
        if inputs.where is not None and c.change is not None:
            c.where = inputs.where(c.change)
    best = cands[0] if cands else None
    change = best.change if best is not None and best.change is not None else 0.0
    e = Explanation(cands, fit.chi0, fit.n, remainder=np.where(ok, S - R - change, 0.0),
                    where=inputs.where(S - R) if inputs.where is not None else "")
    (claim or share_rule)(e, fit, inputs)
    e.sentence, e.headline = explanation_words(e)
    e.seconds = time.perf_counter() - t0
    return e


def rank(cands: list[Candidate], fit: Fit) -> list[Candidate]:
    """Each candidate's share of the excess chi^2, best first (a catalogued bug first on a tie).

    What noise alone leaves: n terms of about 1 (less where the cap bites
    on heavy tails), or what the best candidate leaves if that is less.
    Each fitted parameter costs ln(n) (the Bayesian information criterion):
    a surface's three albedos do not win over a fixed bug by fitting the noise.
    """
    pen = math.log(max(fit.n, 2))
    for c in cands:
        c.chi2 = c.chi2 + c.params * pen
    floor = min([float(fit.n)] + [c.chi2 for c in cands])
    excess = fit.chi0 - floor
    for c in cands:
        c.explained = float(min((fit.chi0 - c.chi2) / excess, 1.0)) if excess > 0 else 0.0
    cands.sort(key=lambda c: (-c.explained, c.params))
    return _catalogue_first(cands)


def _catalogue_first(cands: list[Candidate]) -> list[Candidate]:
    """A catalogued bug within TIE of the best goes first (it names a known bug; see mcrt.grade.explain)."""
    if not cands or cands[0].catalogue:
        return cands
    top = cands[0].explained
    cat = next((c for c in cands if c.catalogue and c.explained >= top - TIE), None)
    if cat is None:
        return cands
    return [cat] + [c for c in cands if c is not cat]
