"""What the explanation stage compares: candidate explanations of a failing image, and its answer.

A *candidate* is one mistake with its parameters fitted in the student's
terms: a family of mistakes at its best fit (the floor's albedo 0.40, the
light moved by +1 along x, a tone curve) or a catalogued estimator bug. Each
predicts a change to the image, ``change`` = M - R (its model image less the
reference), from which the stage scores it. A *family* turns the image into
candidates (:class:`Family`); the engine (:func:`mcrt.grade.explain.explain`)
runs every family, ranks the candidates by the share of the difference each
explains, and a *claim rule* (:class:`ClaimRule`) decides what the feedback
may say about the best one. The answer is an :class:`Explanation`: the best
candidate, its share, and the *remainder* (hand-in minus reference minus the
best candidate's change), which a claim rule can test with the bias test's
noise model (:attr:`Inputs.test_remainder`).

Nothing here computes anything: the engine, the families and the rules live
in :mod:`mcrt.grade.explain`; this module is the contract between them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from mcrt.util.jsonsafe import json_safe

#: Floor of the relative error no two renderers share: every chi^2 that compares a model image with a hand-in
#: adds (FLOOR * R)^2 to each term's variance.
FLOOR = 0.002
#: Two candidates whose shares differ by less than this are tied: a catalogued bug within TIE of the best is
#: named first (it names a known bug), another family within TIE of the claimed one is mentioned beside it.
TIE = 0.02

#: What a claim rule may conclude (:attr:`Explanation.verdict`).
CLAIMED = "claimed"  # the best candidate is the cause: "It looks like ..."
PARTIAL = "partial"  # it explains part of the difference and something else is wrong (where: Explanation.remainder)
INDISTINCT = "indistinct"  # it fits, but no better than noise would let anything fit
DESCRIBED = "described"  # only a description fits (Candidate.describes): how the image differs, with no cause
AMBIGUOUS = "ambiguous"  # causes of other readings leave noise as well, none significantly better: no cause claimed
NONE = "none"  # nothing explains most of the difference
VERDICTS = (CLAIMED, PARTIAL, INDISTINCT, DESCRIBED, AMBIGUOUS, NONE)


@dataclass
class Candidate:
    """One explanation of a hand-in's difference from the reference.

    A family fills ``family`` to ``change``; the engine fills ``explained``
    and ``where``. Rankings of the catalogue by tile, pixel or noise
    statistics (:mod:`mcrt.grade.explain.catalogue`) also fill ``amplitude``
    and ``chi2_fit`` (the chi^2 at the fitted amplitude).
    """

    family: str  # 'albedo', 'light_position', 'fov', 'catalogue', ... (what the scoring stage weighs)
    name: str  # what it names, unique among the candidates: 'albedo of wall DE', 'nee_no_area'
    text: str  # one clause in the student's terms, to follow "It looks like": 'the floor with albedo 0.40 where ...'
    chi2: float  # chi^2 of R + change against the hand-in (Fit.delta(change)); the engine adds params * ln(n)
    params: int = 0  # parameters fitted to the image (each costs ln n, the Bayesian information criterion)
    explained: float = 0.0  # share of the excess chi^2 removed (set by the engine)
    value: object = None  # the fitted parameters in the student's terms (JSON-able: numbers, strings, tuples)
    catalogue: bool = False  # a catalogued estimator bug (named first on a tie: it names a known bug)
    change: np.ndarray | None = None  # the predicted change M - R, (H, W, 3) at the grade resolution
    where: str = ""  # where the change lies, in words (set by the engine for the best few)
    amplitude: float | None = None  # catalogue rankings only: the fitted amplitude of the bug's signature
    chi2_fit: float | None = None  # catalogue rankings only: chi^2 at that amplitude
    ranked: bool = False  # from a catalogue ranking (tile, pixel or noise statistics) rather than a model-image fit
    # Families with more parameters that are another reading of the same image, not a generalisation of this one
    # (a curve on the values beside a per-sample clamp): named beside it where their remainder is noise too
    # (mcrt.grade.adequacy.claim_rule), whatever Occam's rule prefers.
    rivals: tuple[str, ...] = ()
    # Families this one nests (a scale per channel nests one scale): it fitting as well is no other cause for them
    # (mcrt.grade.adequacy.unconfirmed).
    generalises: tuple[str, ...] = ()
    # A description of how the image differs rather than a mistake a program makes (any monotone curve through the
    # values, which a material or the light can mimic): it may leave noise, but it is said, never claimed.
    describes: bool = False
    # A fit flexible enough to take up a share of any difference: a parameter per object (several surfaces' colours
    # at once) takes up what sits on objects (a vignette, the light moved, a tone curve); a choice among many
    # rearrangements of the values (mcrt.grade.explain.stride) that of any image darker than the render. Claimed only
    # where its remainder is noise and no other candidate's is, and it never leads a partial reading nor stands as
    # the closest cause (mcrt.grade.adequacy.claim_rule).
    flexible: bool = False
    # A property of a surface no pixel sees directly (a wall behind the camera): its fit rests on the light that
    # surface reflects onto what is seen, which other mistakes change alike (a biased estimator, a path cut short).
    # It may leave noise, but it is never claimed on that alone (mcrt.grade.adequacy.claim_rule).
    out_of_view: bool = False
    # The change multiplies light the program renders with its noise (a light sample's or a path's weight off by a
    # factor): the hand-in's noise grows with it, which the remainder test allows (mcrt.grade.stages.explanation).
    gain: bool = False
    # The hand-in's noise variance (H, W, 3) the change implies, where a curve on the values bends the render's noise
    # (mcrt.grade.explain.fit.bent_noise): the remainder test allows its growth over the model's.
    noise: np.ndarray | None = None

    def to_dict(self) -> dict:
        if self.ranked:
            return {"mutant": self.name, "description": self.text, "chi2": self.chi2, "chi2_best_amplitude": self.chi2_fit,
                    "amplitude": self.amplitude, "explained": self.explained, "where": self.where}
        return {"mutant": self.name, "family": self.family, "description": self.text, "explained": self.explained,
                "chi2": self.chi2, "value": json_safe(self.value), "catalogue": self.catalogue, "where": self.where,
                "amplitude": None, "chi2_best_amplitude": None}


@dataclass
class Inputs:
    """What every family may use besides the image (the engine builds it once per hand-in).

    ``test_remainder(resid)`` runs the pipeline's bias test (same noise
    model, tiles and level) on a residual (H, W, 3) and returns its
    :class:`mcrt.stats.onesample.MultiScaleTest`; None where the caller
    has no noise model (then no remainder can be tested).
    """

    basis: object  # mcrt.grade.explain.basis.Basis: mcrt renders of the scene's variations (mcrt.grade.explain.basis.prepare_basis)
    mutants: dict = field(default_factory=dict)  # catalogue name -> mcrt.grade.expected.Expected
    baseline: object = None  # the catalogue's bug-free Expected image (same seed as the mutants)
    texts: dict[str, str] = field(default_factory=dict)  # catalogue name -> its description
    labels: np.ndarray | None = None  # (H, W) surface index per pixel (mcrt.grade.expected.surface_labels)
    label_names: tuple[str, ...] = ()  # surface index -> 'the floor', 'wall DE (blue)', ...
    where: Callable[[np.ndarray], str] | None = None  # words for where a change (H, W, 3) lies
    test_remainder: Callable[[np.ndarray], object] | None = None


class Family(Protocol):
    """A family of mistakes: fits its parameters to the hand-in and returns its candidates.

    ``fit`` (:class:`mcrt.grade.explain.fit.Fit`) holds the hand-in S, the
    reference R, the difference D = S - R, the pixels to use and the chi^2
    weights; ``fit.delta(change)`` is the chi^2 a predicted change leaves.
    Return the family's best fit (or one candidate per sub-family); each
    candidate's ``chi2`` is ``fit.delta(change)`` at its fitted parameters.
    An optional attribute ``prepare(a, scene, render)`` renders what the
    family needs, once per machine (``render`` is the grading cache's,
    see :func:`mcrt.grade.explain.families.prepare`); its result is kept
    in ``Basis.extra[name]`` (``inputs.basis.extra[name]`` at grade time).
    """

    name: str

    def __call__(self, fit, inputs: Inputs) -> list[Candidate]: ...


@dataclass
class Explanation:
    """The explanation stage's answer (see the module docstring)."""

    candidates: list[Candidate]  # best first (a catalogued bug within TIE of the best goes first)
    chi2_none: float  # chi^2 of the reference itself (no change)
    terms: int  # terms in every chi^2 (what noise alone gives, about)
    remainder: np.ndarray  # S - R - best.change (S - R when there is no candidate), 0 where not used
    verdict: str = NONE  # one of VERDICTS, set by the claim rule
    sentence: str = ""  # for the bias test's output (set by mcrt.grade.feedback.explanation_words)
    headline: str = ""  # for the summary
    where: str = ""  # where S - R lies, in words
    remainder_where: str = ""  # where the remainder lies, when the rule found it structured (PARTIAL); for NONE,
    # where the difference itself lies (the adequacy rule, by object)
    adequacy: object = None  # what the claim rule measured of the remainder (mcrt.grade.adequacy.Adequacy), if it did
    broader: tuple[str, str] | None = None  # PARTIAL: (family, words) of what the lead and its remainder point to
    # together (mcrt.grade.broader), if they do
    seconds: float = 0.0

    @property
    def best(self) -> Candidate | None:
        return self.candidates[0] if self.candidates else None

    @property
    def explained(self) -> float:
        return self.best.explained if self.best is not None else 0.0

    @property
    def named(self) -> Candidate | None:
        """The claimed cause: the best candidate when the verdict is CLAIMED, else None."""
        return self.best if self.verdict == CLAIMED else None

    def to_dict(self) -> dict:
        named = self.named
        return {"chi2_none": self.chi2_none, "terms": self.terms, "named": named.name if named else None,
                "family": named.family if named else None, "sentence": self.sentence,
                "where": self.where, "seconds": self.seconds, "verdict": self.verdict,
                "adequacy": self.adequacy.to_dict() if self.adequacy is not None else None,
                "broader": self.broader[0] if self.broader else None,
                "candidates": [c.to_dict() for c in self.candidates[:8]]}


class ClaimRule(Protocol):
    """Decides what the feedback may claim: sets ``e.verdict`` (one of VERDICTS) and, for PARTIAL,
    ``e.remainder_where``. ``fit`` is the engine's :class:`~mcrt.grade.explain.fit.Fit`."""

    def __call__(self, e: Explanation, fit, inputs: Inputs) -> None: ...
