r"""The weight a path carries on from a surface hit off by a constant: at one hit, or at every hit from one on.

With :math:`D_k` the basis's render cut at depth k (Mitsuba's convention:
:math:`D_1` the light seen directly, :math:`D_2 - D_1` the direct light on
the first surface seen) and :math:`L_j = D_j - D_{j-1}` the light of paths of
exactly j segments, a path of j segments has carried on (been continued by a
sampled ray) from hits 1 to j - 2; the light sampled at each hit is not
touched. The model images are

* **once**, the weight of the ray traced on from hit s scaled by q (n rays
  from the first hit summed where they should be averaged is q = n, s = 1):
  :math:`R + (q - 1)(R - D_{s+1})`;
* **from s on**, every continuation from hit s on scaled by q (a sampling
  pdf off by a constant: the cosine pdf without its 1/pi is q = 1/pi, s = 1;
  Russian roulette whose survivors are divided by the wrong probability, or
  by none, from hit s): :math:`R + \sum_{j \ge s+2} (q^{\,j-1-s} - 1) L_j`.

q is not fitted freely: a free factor near 1 fits any small change of the
indirect light (a biased estimator's, a shadow ray's bug, a path depth off
by one), which is no weight a program gets wrong. It is one of the factors
programs produce (:data:`FACTORS`): n rays summed, pi or 1/pi, and
roulette's weights for the usual survival probabilities p (p without a
division, 1/p with the losers not stopped, p / (1 - p) divided by the
probability of stopping). One parameter each (s and the factor scanned);
nothing is rendered: the depth renders are the basis's, with its seed, so
the L_j share its random numbers.
"""

from __future__ import annotations

import math

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.light_twice import _depth

#: The surface hits s the scale may start at.
HITS = (1, 2, 3, 4, 5)
#: Roulette's usual survival probabilities.
_SURVIVAL = (0.5, 0.75, 0.8)
#: The numbers of rays a program traces on from a hit (and may sum where their mean belongs).
SUMMED = (2.0, 3.0, 4.0, 8.0, 16.0)
#: The factors q a program's mistake gives a path's weight: n rays summed where their mean belongs, a pi too many
#: or too few, and roulette's survivors weighed p, 1/p or p / (1 - p) (the module docstring).
FACTORS = tuple(sorted({*SUMMED, math.pi, 1.0 / math.pi}
                       | {round(q, 6) for p in _SURVIVAL for q in (p, 1.0 / p, p / (1.0 - p))} - {1.0}))


def _ordinal(n: int) -> str:
    return {1: "first", 2: "second", 3: "third", 4: "fourth", 5: "fifth"}.get(n, f"{n}th")


#: Where the two shapes differ most, in the deepest paths, the basis's own noise is largest (the deep paths' light
#: times q^6): the shape that fits best is no evidence of which mistake it is, and either's words name the mistakes of
#: both, the likeliest first.
ROULETTE = "Russian roulette's survivors divided by the wrong probability (the probability of stopping, or none)"
#: Where the light of long paths alone is darker (from :data:`CLAMP_FROM` hits on, by a factor of at least
#: :data:`CLAMP_LEAST`), its rare bright samples clamped or dropped darken it as well: a firefly clamp on the light
#: that bounces and the robust means (trimmed, median, with outliers rejected) fit these shapes as closely as a
#: weight does (seen in the grading-accuracy classes: each such estimator fitted a factor of 0.75 to 0.8 from the
#: third or fourth hit on; a half of that light is more than they drop), and the words name them beside the weight.
CLAMP_FROM = 3
CLAMP_LEAST = 0.7
CLAMP = ("or the long paths' rare bright samples clamped or dropped (a firefly clamp on the light that bounces, a "
         "trimmed or median mean, outliers rejected)")


def _clamp(q: float, s: int) -> str:
    """:data:`CLAMP`'s words where the factor and the first hit are a clamp's or a robust mean's, else none."""
    return f", {CLAMP}" if s >= CLAMP_FROM and CLAMP_LEAST <= q < 1.0 else ""


def _once_words(q: float, s: int) -> str:
    summed = f"{q:.0f} rays traced on from it summed where their mean belongs, " if q in SUMMED else ""
    return (f"the light that bounces on from the {_ordinal(s)} surface hit {q:.2f} times what it should be (the light "
            f"sampled there right): as with {summed}a weight off by a constant at that bounce (a pdf or a BRDF factor "
            f"there), or {ROULETTE}{_clamp(q, s)}")


def _from_words(q: float, s: int) -> str:
    why = ("the cosine-weighted pdf written cos(theta) without its 1/pi (each diffuse bounce weighing albedo / pi), "
           if abs(q - 1 / math.pi) <= 0.03 else "a pdf with pi where 1/pi belongs, " if abs(q - math.pi) <= 0.3 else "")
    return (f"the weight a path carries on with {q:.2f} times what it should be at every surface hit from the "
            f"{_ordinal(s)} on (the light sampled at each hit right): as with {why}a sampling pdf off by a constant, "
            f"or {ROULETTE}{_clamp(q, s)}")


def path_weight(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The best start s and factor q of :data:`FACTORS` for each shape (once, from s on; the module docstring)."""
    b = inputs.basis
    depths = [_depth(b, k) for k in range(1, b.max_depth + 1)]
    if any(d is None for d in depths):
        return []
    L = [depths[0]] + [depths[j] - depths[j - 1] for j in range(1, len(depths))]  # L[j - 1]: paths of j segments
    R = depths[-1]

    def once(s):
        rest = R - depths[s]  # the light of paths of s + 2 segments or more
        return lambda q: (q - 1.0) * rest

    def from_on(s):
        return lambda q: sum((q ** (j - 1 - s) - 1.0) * L[j - 1] for j in range(s + 2, len(L) + 1))

    out = []
    for shape, model, words in (("once", once, _once_words), ("from", from_on, _from_words)):
        fits = [(fit.delta(change), s, q, change) for s in HITS if s + 2 <= len(L) for q in FACTORS
                for change in (model(s)(q),)]
        if fits:
            chi, s, q, change = min(fits, key=lambda t: t[0])
            out.append(Candidate("path_weight", f"path weight {shape}", words(q, s), chi, 1,
                                 value={"shape": shape, "hit": s, "factor": q}, change=change, gain=True))
    return out


path_weight.name = "path_weight"
