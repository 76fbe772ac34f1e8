r"""Is a fitted cause enough? The remainder tested as the hand-in was.

A candidate explanation (a family's best fit, :mod:`mcrt.grade.explain`)
predicts a change :math:`\Delta` of the reference R. What it leaves,

.. math::

    r = S - R - \Delta,

is tested with the bias test itself (:func:`mcrt.grade.score.bias_test`:
the same noise model, tiles, Holm family at the same ``alpha`` and the same
relevance threshold ``min_effect``), with the per-object test of
:mod:`mcrt.grade.objects` in its family and the candidate's own noise
(``extra_var``: the basis renders' variance) added to the reference's. Then:

* **adequate**: nothing is rejected: the remainder is consistent with noise,
  and the cause may be claimed ("It looks like ...");
* **partial**: the candidate explains a share of the difference but a
  structured remainder is left: it is named as partial, with the share and
  the objects the remainder sits on ("partly like X, which explains 56 %;
  something else is wrong on the ceiling and the light");
* **none**: no candidate explains enough (:data:`PARTIAL` of the
  difference) to be mentioned: the objects the difference sits on are named
  instead, with how they differ.

The checks that print findings of their own (a filtered image, a camera that
does not match, an exposure factor) go through :func:`remainder_test` too:
the finding's own model is the candidate (for an exposure factor k,
:math:`\Delta = (k - 1) R`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mcrt.grade import objects as obj
from mcrt.grade.score import Noise, bias_test

#: A candidate that explains less than this share of the difference is not mentioned at all.
PARTIAL = 0.3


@dataclass
class Adequacy:
    """The verdict on one candidate and where its remainder lies."""

    verdict: str  # 'adequate', 'partial' or 'none'
    explained: float  # share of the difference the candidate explains (0 for none)
    rejected: int  # remainder tests rejected and relevant (tiles and objects)
    n_tests: int
    objects: list[int] = field(default_factory=list)  # labels the remainder sits on, largest first
    where: str = ""  # those objects in words, with how they differ
    map: np.ndarray | None = None  # (H, W) per-object relative difference of the remainder (rejected objects)
    excess_rms: float = 0.0  # the remainder's bias beyond noise, relative
    alternatives: list[str] = field(default_factory=list)  # families that fit as well (adequate too)

    def to_dict(self) -> dict:
        return {"verdict": self.verdict, "explained": self.explained, "rejected": self.rejected,
                "n_tests": self.n_tests, "objects": self.objects, "where": self.where,
                "remainder_excess_rms": self.excess_rms, "alternatives": self.alternatives}


@dataclass
class Scene2D:
    """What the remainder test needs besides the images: the bias test's settings and the surface labels."""

    tiles: tuple
    alpha: float
    min_effect: float
    full_effect: float
    labels: np.ndarray  # (H, W) surface index
    names: tuple[str, ...]  # label names (the last is 'nothing')


def remainder_test(S: np.ndarray, R: np.ndarray, delta: np.ndarray | float, mask: np.ndarray, noise: Noise,
                   sc: Scene2D, *, extra_var: np.ndarray | None = None, explained: float = 1.0) -> Adequacy:
    """Test S - R - delta (the module docstring); ``explained`` is the candidate's share, for the verdict's words."""
    S, R = np.asarray(S, np.float64), np.asarray(R, np.float64)
    d = np.broadcast_to(np.asarray(delta, np.float64), S.shape)
    ok = mask & np.isfinite(S).all(axis=-1) & np.isfinite(d).all(axis=-1)
    resid = np.where(ok[..., None], S - R - d, 0.0)
    nz = Noise(model=noise.model, reference=noise.reference + (extra_var if extra_var is not None else 0.0),
               pair=noise.pair)
    K = len(sc.names) - 1
    ot = obj.object_tests(resid, R, ok, nz, sc.labels, K)
    bt = bias_test(resid, R, ok, nz, sc.tiles, alpha=sc.alpha, min_effect=sc.min_effect,
                   full_effect=sc.full_effect, extra=[ot.family(sc.min_effect)])
    rej_o = bt.extra.get("objects", np.zeros(K * 3, bool)).reshape(K, 3)
    n_rej = sum(int(np.count_nonzero(s.penalised)) for s in bt.scales) + int(np.count_nonzero(rej_o))
    n_tests = bt.n_tests + K * 3
    if n_rej == 0:
        return Adequacy("adequate", explained, 0, n_tests, excess_rms=bt.excess_rms)
    where = obj.flagged_objects(ot, rej_o, tile_effect=bt.pixel_effect, labels=sc.labels, mask=ok)
    nv = nz.model + nz.reference
    words = obj.sentence(S - d, R, ok, nv, sc.labels, sc.names, where)
    verdict = "partial" if explained >= PARTIAL else "none"
    return Adequacy(verdict, explained, n_rej, n_tests, where, words, obj.effect_map(ot, rej_o, sc.labels, ok),
                    bt.excess_rms)


def claim(text: str, ad: Adequacy, *, alt: str = "") -> tuple[str, str]:
    """(sentence, headline) for a candidate ``text`` ('the light moved by +1 along y') and its verdict."""
    pct = f"{100 * ad.explained:.0f} %"
    if ad.verdict == "adequate":
        s = f"It looks like {text}: what is left after it is consistent with noise ({pct} of the difference explained)"
        if alt:
            return (s + f"; so would {alt}: the image cannot tell them apart.",
                    f"It looks like {text}, or {alt.split(', ')[0]}.")
        return s + ".", f"It looks like {text}."
    if ad.verdict == "partial":
        rest = f"something else is wrong {ad.where}" if ad.where else "something else is wrong as well"
        s = (f"Partly like {text}, which explains {pct} of the difference; {rest} (what is left after that "
             f"explanation is not noise: {ad.rejected} of {ad.n_tests} tests of it are significant).")
        return s, f"Partly like {text}; {rest}."
    where = f"The difference sits {ad.where}" if ad.where else "The difference has no single place"
    s = ("No single mistake we tried explains the difference well enough to name it. " + where + ".")
    return s, (f"No single mistake we tried explains the difference; it sits {ad.where}." if ad.where
               else "No single mistake we tried explains the difference.")



#: How many of the best candidates are tried, in order, for one whose remainder is noise.
TRIED = 3
#: Another family within this share of the claimed one whose remainder is noise too is named beside it: the
#: image cannot tell the two apart.
AMBIGUOUS = 0.05


def judge(e, S: np.ndarray, R: np.ndarray, mask: np.ndarray, noise: Noise, sc: Scene2D, *,
          extra_var=None, claimable=None):
    """Apply the rule to an explanation ``e`` (:class:`mcrt.grade.explain.Explanation`): (the explanation with
    ``named``, ``sentence`` and ``headline`` rewritten, the :class:`Adequacy` of what it says).

    The first of the :data:`TRIED` best candidates that ``claimable(c)`` allows
    (default: explaining at least :data:`mcrt.grade.explain.NAMED`; the
    explanation's own rule for the best) and whose remainder is noise is
    claimed; else the best is partial if it explains :data:`PARTIAL`, else
    nothing is named and the difference itself is placed on objects.
    ``extra_var(c)`` is the noise (H, W, 3) of candidate c's predicted change
    (None: none).
    """
    from dataclasses import replace

    from mcrt.grade.explain import NAMED

    def var(c):
        return extra_var(c) if extra_var is not None else None

    def ok(c):
        return c.delta is not None and (claimable(c) if claimable is not None else c.explained >= NAMED)

    cands = [c for c in e.candidates[:TRIED] if ok(c)]
    if e.named is not None and e.named in cands:  # the explanation's own choice first (a catalogued bug in a tie)
        cands = [e.named] + [c for c in cands if c is not e.named]
    first = None
    for c in cands:
        ad = remainder_test(S, R, c.delta, mask, noise, sc, extra_var=var(c), explained=c.explained)
        if ad.verdict == "adequate":
            alts = [a for a in cands if a is not c and a.family != c.family and a.explained >= c.explained - AMBIGUOUS
                    and remainder_test(S, R, a.delta, mask, noise, sc, extra_var=var(a)).verdict == "adequate"]
            ad.alternatives = [a.family for a in alts]
            s, h = claim(c.text, ad, alt=" or ".join(f"{a.text}, {100 * a.explained:.0f} %" for a in alts))
            return replace(e, named=c, sentence=s + (f" It changes the image {c.where}." if c.where else ""),
                           headline=h), ad
        first = first or (c, ad)
    best = e.candidates[0] if e.candidates else None
    if first is not None and first[0] is best:
        c, ad = first
    elif best is not None and best.explained >= PARTIAL and best.delta is not None:
        c = best
        ad = remainder_test(S, R, c.delta, mask, noise, sc, extra_var=var(c), explained=c.explained)
    else:
        c = None
    if c is None or ad.verdict != "partial":
        ad = remainder_test(S, R, 0.0, mask, noise, sc, explained=0.0)
        ad.verdict = "none" if ad.rejected else "adequate"
        if ad.verdict == "adequate":  # the difference itself is noise at this level: nothing to place
            return replace(e, named=None), ad
        s, h = claim("", ad)
        return replace(e, named=None, sentence=s, headline=h), ad
    s, h = claim(c.text, ad)
    return replace(e, named=None, sentence=s, headline=h), ad
