r"""Is a fitted cause enough? The remainder tested as the hand-in was.

A candidate explanation (a family's best fit, :mod:`mcrt.grade.explain`)
predicts a change :math:`\Delta` of the reference R. What it leaves,

.. math::

    r = S - R - \Delta,

is tested with the bias test itself (:func:`mcrt.stats.onesample.multiscale_test`:
the same noise model, tiles, Holm family at the same ``alpha`` and the same
relevance threshold ``min_effect``), with the per-object tests of
:mod:`mcrt.grade.objects` (means and zero-mean structure) in its family and the candidate's own noise
(``extra_var``: the basis renders' variance) added to the reference's. Then:

* **adequate**: nothing is rejected: the remainder is consistent with noise,
  and the cause may be claimed ("It looks like ...");
* **partial**: the candidate explains a share of the difference but a
  structured remainder is left: it is named as partial, with the share and
  the objects the remainder sits on ("partly like X, which explains 56 %;
  something else is wrong on the ceiling and the light"); where the
  candidate and its remainder point to one part of the program together (an
  object's geometry, faces missing from the room: :mod:`mcrt.grade.broader`),
  that part is said too, and only it is named;
* **none**: no candidate explains enough (:data:`PARTIAL_LEAD` of the
  difference) to lead: the objects the difference sits on are named
  instead, with how they differ, and the closest cause with its share.

Beside a partial reading that points to nothing broader, and beside none,
the difference as a whole is tried as the bounced light alone changed,
the direct light right (:func:`mcrt.grade.broader.bounced_light`), then as
the first surface's direct light alone changed, the light seen and the
bounced light right (:func:`mcrt.grade.broader.direct_light`), which the
words say where one holds.

**Black where the light reaches is never noise.** A sample of a surface the
light reaches directly is never 0, so a hand-in's pixels 0 in every channel
there (:func:`mcrt.grade.explain.pixels.black_holes`: a face missing, the void seen through it, a
surface black, pixels never written) are explained only by a change that
makes them dark: a candidate whose prediction keeps :data:`HOLE_LIT` of the
reference's light on enough of them (:func:`holes_left`) is not adequate,
however small its chi^2 there (a wall's colour fitted a tenth of the
scene's reads a missing wall within a noise model made for lit pixels), and
the surfaces the holes lie on are where its remainder is.

**A claim must beat every other reading that leaves noise.** Occam's rule
picks among candidates; it does not say the image confirmed the pick. The
BIC's credit for fewer parameters is largest where two predictions are
nearly the same, where the image cannot tell them apart. So the claimed
candidate must also fit better than every adequate candidate of another
reading (:data:`READINGS`: families that name other mistakes, not a
generalisation or rewording of it) by :data:`CONFIRM_Z`, by
:func:`closeness` *without* that credit (:func:`unconfirmed`). Otherwise the
verdict is AMBIGUOUS: "it could be X, or Y: the image cannot tell which",
and no cause is claimed. A colour of a surface that no pixel sees directly
(a wall behind the camera) is never claimed on a fit alone: it shows only in
the light that surface reflects onto the rest, which other mistakes change
alike (a biased estimate of each pixel, paths cut short), so its verdict is
AMBIGUOUS too, beside whatever else leaves noise.

**Which adequate candidate is claimed (Occam's rule).** Several candidates
can leave noise: a small darkening of the room is a path cut one bounce
short, a wall's three albedos, or a curve through the values. Adequacy says
that each fits to within noise; it does not say which to believe. The rule
claims the *simplest adequate explanation*: of the candidates whose remainder
is noise (the best of a few families, :func:`tried_candidates`), the one with
the fewest fitted parameters (:func:`occam`), unless one with more fits
significantly better, by Vuong's closeness test for models that are not
nested (:func:`closeness`: the BIC-adjusted sum of the term-by-term
differences of their chi-squares over its spread, against :data:`OCCAM_Z`).
A candidate that does not fit better than no change at all, by the same
criterion (:func:`beats_no_change`), is never tried: where the difference is
close to noise, a field of view fitted to the scene's own or a blur of a
tenth of a pixel leaves noise too, and must not be named as a possibility.
A more complex family that fits only insignificantly better is not claimed,
nor named beside the claim; another family with no more parameters that
explains as much (:data:`AMBIGUOUS`) and leaves noise too is named beside it:
"so would Y: the image cannot tell them apart". A family with more
parameters that is another reading of the image rather than a generalisation
of the claimed one (a curve on the values beside a per-sample clamp,
:attr:`mcrt.grade.candidates.Candidate.rivals`) is named beside it too where
it leaves noise: Occam's rule then says which reading is simpler, not that
the other is wrong.

The checks that print findings of their own follow the same rule: the
exposure criterion claims a constant factor only where the image divided by
it passes the bias test (:mod:`mcrt.grade.stages.exposure`); the filter,
camera and wrong-pixels findings stand beside an unexplained difference only
where they hold on what the best candidate leaves
(:mod:`mcrt.grade.stages.bias`). :func:`claim_rule` is the rule as the
explanation engine takes it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mcrt.grade import broader
from mcrt.grade.explain.pixels import MIN_HOLES, black_holes
from mcrt.grade import objects as obj
from mcrt.stats.onesample import Noise, multiscale_test

#: A candidate that explains less than this share of the difference is not mentioned at all.
PARTIAL_SHARE = 0.3
#: A candidate leads a partial reading ("partly like X; something else is wrong") only where it explains at least this
#: share: "partly like" a cause that leaves most of the difference sends a student to a step that may not be wrong
#: (a grey image for a camera aimed elsewhere); below it, nothing is claimed, the difference is placed on objects and
#: the closest cause is named with its share.
PARTIAL_LEAD = 0.5


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
    alternatives: list[tuple] = field(default_factory=list)  # (family, text, share) of causes that fit as well
    also_adequate: list[tuple] = field(default_factory=list)  # (family, params, closeness z of the claim over it)

    def to_dict(self) -> dict:
        return {"verdict": self.verdict, "explained": self.explained, "rejected": self.rejected,
                "n_tests": self.n_tests, "objects": self.objects, "where": self.where,
                "remainder_excess_rms": self.excess_rms, "alternatives": [a[0] for a in self.alternatives],
                "also_adequate": [list(a) for a in self.also_adequate]}


@dataclass
class Scene2D:
    """What the remainder test needs besides the images: the bias test's settings and the surface labels."""

    tiles: tuple
    alpha: float
    min_effect: float
    full_effect: float
    labels: np.ndarray  # (H, W) surface index
    names: tuple[str, ...]  # label names (the last is 'nothing')
    shares: np.ndarray | None = None  # (K, tails) each object's share in each of the noise's tails in a correct render
    filtered: bool = False  # the blur or correlated-noise detector found a filter over the image
    misregistered: bool = False  # the registration test found the image's edges displaced against the reference's
    refitted: bool = False  # the image was decoded with a curve fitted to it, not its declared one


def remainder_test(S: np.ndarray, R: np.ndarray, delta: np.ndarray | float, mask: np.ndarray, noise: Noise,
                   sc: Scene2D, *, extra_var: np.ndarray | None = None, explained: float = 1.0,
                   structure: bool = True, holes: np.ndarray | None = None) -> Adequacy:
    """Test S - R - delta (the module docstring); ``explained`` is the candidate's share, for the verdict's words;
    ``structure``: with the per-object structure test (:func:`mcrt.grade.objects.structure_family`); ``holes``: the
    hand-in's black pixels where the light reaches (:func:`mcrt.grade.explain.pixels.black_holes`), which a change
    that lights them leaves (:func:`holes_left`)."""
    S, R = np.asarray(S, np.float64), np.asarray(R, np.float64)
    d = np.broadcast_to(np.asarray(delta, np.float64), S.shape)
    ok = mask & np.isfinite(S).all(axis=-1) & np.isfinite(d).all(axis=-1)
    resid = np.where(ok[..., None], S - R - d, 0.0)
    nz = Noise(model=noise.model, reference=noise.reference + (extra_var if extra_var is not None else 0.0),
               pair=noise.pair)
    K = len(sc.names) - 1
    ot = obj.object_tests(resid, R, ok, nz, sc.labels, K)
    # The body's edge only (the first tail): a remainder holds the fitted change's own errors (its renders' noise,
    # known only roughly, and a first-order model's), which land in the outer tails of a bright or large change.
    name, p, rel, share = obj.structure_family(resid, R, ok, nz, sc.labels, K, sc.min_effect, sc.shares,
                                                image=np.where(ok[..., None], S, 0.0), tails=1)
    # Structure the candidate leaves counts where it left most of the object's difference (a glossy sphere read
    # as a blur), not where it fits the object but for a trace of its shape that high spp shows.
    rel = rel & (_energy(resid, ok, sc.labels, K) >= LEFT * _energy(np.where(ok[..., None], S - R, 0.0), ok, sc.labels, K))
    bt = multiscale_test(resid, R, ok, nz, sc.tiles, alpha=sc.alpha, min_effect=sc.min_effect, full_effect=sc.full_effect,
                         extra=[ot.family(sc.min_effect)] + ([(name, p, rel, share)] if structure else []))
    # An object whose structure test rejects is placed as one whose mean does (every channel).
    rej_s = bt.extra.get("object_structure", np.zeros(K, bool))
    rej_o = bt.extra.get("objects", np.zeros(K * 3, bool)).reshape(K, 3) | rej_s[:, None]
    n_rej = sum(int(np.count_nonzero(s.penalised)) for s in bt.scales) + int(np.count_nonzero(rej_o))
    n_tests = bt.n_tests + K * 4
    left = holes_left(R, d, holes, nz.reference, sc.labels)
    n_rej += left is not None
    if n_rej == 0:
        return Adequacy("adequate", explained, 0, n_tests, excess_rms=bt.excess_rms)
    where = obj.flagged_objects(ot, rej_o, tile_effect=bt.pixel_effect, labels=sc.labels, mask=ok)
    if left is not None:  # the holes' surfaces, most of them first, after the tests' own
        k, n = np.unique(sc.labels[left], return_counts=True)
        where = list(where) + [int(x) for x in k[np.argsort(-n, kind="stable")] if int(x) not in where]
    nv = nz.model + nz.reference
    words = obj.sentence(S - d, R, ok, nv, sc.labels, sc.names, where)
    verdict = "partial" if explained >= PARTIAL_SHARE else "none"
    return Adequacy(verdict, explained, n_rej, n_tests, where, words, obj.effect_map(ot, rej_o, sc.labels, ok),
                    bt.excess_rms)


#: A change lights a hole where its prediction there is at least this share of the reference's luminance (a surface
#: of a fiftieth of its albedo is dark, not black: a sample of it is never 0).
HOLE_LIT = 0.02
#: ... by this many standard errors of the prediction's noise over a surface's holes.
HOLE_Z = 4.0
def holes_left(R: np.ndarray, delta: np.ndarray, holes: np.ndarray | None, var: np.ndarray,
               labels: np.ndarray) -> np.ndarray | None:
    """(H, W) the ``holes`` (:func:`mcrt.grade.explain.pixels.black_holes`) a change ``delta`` of R lights, where
    they are at least :data:`~mcrt.grade.explain.pixels.MIN_HOLES` of the pixels; else None. A surface's holes are
    lit where the prediction's luminance over them exceeds :data:`HOLE_LIT` of R's by :data:`HOLE_Z` standard errors
    (``var``: the prediction's noise per pixel, the reference's and the change's own: a change rendered with the
    surface black still carries their noise there)."""
    if holes is None:
        return None
    lum, pred, v = R @ obj.LUMINANCE, (R + delta) @ obj.LUMINANCE, var @ obj.LUMINANCE**2
    left = np.zeros_like(holes)
    for k in np.unique(labels[holes]):
        on = holes & (labels == k)
        if float(np.sum(pred[on] - HOLE_LIT * lum[on])) > HOLE_Z * float(np.sqrt(np.sum(v[on]))):
            left |= on
    return left if int(left.sum()) >= MIN_HOLES * R.shape[0] * R.shape[1] else None


def _energy(x: np.ndarray, mask: np.ndarray, labels: np.ndarray, K: int) -> np.ndarray:
    """(K,) the sum of squared luminance of x over each object's pixels."""
    k = np.where(mask, labels, K).ravel().astype(np.int64)
    return np.bincount(k, (x @ obj.LUMINANCE).ravel() ** 2, minlength=K + 1)[:K]


#: Share of an object's difference a candidate must leave there (explaining at most half of it) for the object's
#: structure to count against it.
LEFT = 0.5
#: Candidates tried for adequacy: the best, in rank order, of the first :data:`TRIED` families among them (two walls'
#: albedos are one family and do not crowd another cause out), at most :data:`MAX_TRIED`.
TRIED = 3
MAX_TRIED = 6
#: Another family within this share of the claimed one whose remainder is noise too, with no more parameters, is
#: named beside it: the image cannot tell the two apart (a family with more parameters that also fits, as a
#: monotone curve fits a constant factor, is no other explanation).
AMBIGUOUS = 0.05
#: Occam's rule: of two adequate candidates, the one with more parameters is claimed only where it fits better
#: than the simpler by at least this many standard deviations of the term-by-term difference of their chi^2
#: (:func:`closeness`, after the BIC's ln n per extra parameter); about 2 % one-sided.
OCCAM_Z = 2.0


def closeness(fit, a, b, *, bic: bool = True) -> float:
    r"""Vuong's closeness statistic of candidate ``a`` over ``b`` (positive: a fits better), BIC-adjusted.

    With :math:`\ell_i` the difference of the two candidates' capped chi^2
    terms (:meth:`mcrt.grade.explain.fit.Fit.terms`, b's minus a's) over
    the n terms,

    .. math::

        z = \frac{\sum_i \ell_i - (p_a - p_b) \ln n}{\sqrt{\sum_i (\ell_i - \bar\ell)^2}}.

    Neither candidate need be nested in the other (a surface's albedo and the
    path depth are not), and neither need be exactly right: the spread of
    :math:`\ell_i` measures how far the image tells the two apart, noise and
    model error together (Vuong 1989, with the Bayesian information
    criterion's correction for the parameters).
    """
    la, lb = fit.terms(a.change), fit.terms(b.change)
    ell = lb - la
    gain = float(np.sum(ell)) - bic * (a.params - b.params) * math.log(max(fit.n, 2))
    sd = float(np.sqrt(np.sum((ell - ell.mean()) ** 2)))
    if sd > 0:
        return gain / sd
    return math.copysign(math.inf, gain) if gain else 0.0


def occam(adequate: list, fit):
    """The simplest adequate candidate that no adequate candidate with more parameters beats by :data:`OCCAM_Z`
    (:func:`closeness`); among equally many parameters, the first in rank order. None when none is adequate."""
    for s in sorted(adequate, key=lambda c: c.params):  # stable: rank order within a count of parameters
        if not any(c.params > s.params and closeness(fit, c, s) >= OCCAM_Z for c in adequate):
            return s
    return None


def beats_no_change(c, fit) -> bool:
    """Whether candidate ``c`` fits better than no change at all by the criterion :func:`closeness` compares
    candidates by (the Bayesian information criterion): its gain in chi^2 over the reference's above its parameters
    times ln n. A candidate that gains less fits noise as well as the difference: however close to noise the
    difference is, the image gives no reason to name it, as a claim or as a possibility."""
    return fit.chi0 - c.chi2 > c.params * math.log(max(fit.n, 2))


def tried_candidates(cands: list, within: float = 0.0, *, fit=None) -> list:
    """The candidates whose remainder is tested: the best (explaining at least :data:`mcrt.grade.explain.NAMED`,
    or with a chi^2 within ``within`` of the best's, with a predicted change) in rank order, of the first
    :data:`TRIED` readings among them (a lower-ranked candidate of those readings is tried after a better one of
    another reading: a new family that fits about as well crowds none of them out; a flexible fit,
    :attr:`mcrt.grade.candidates.Candidate.flexible`, counts as no reading), at most :data:`MAX_TRIED`.

    ``within`` is the spread of noise's chi^2 (the share rule's GAIN_SIGMAS sqrt(2 n)): a candidate the chi^2
    cannot tell from the best fits as well as far as chi^2 can say, whatever share of a small difference it has,
    and its remainder decides. The camera's families are one reading (:func:`_reading`): a shift by a fraction of
    a pixel and a small rotation are one misregistration, and do not crowd another cause out. With ``fit``, a
    candidate that does not fit better than no change (:func:`beats_no_change`) is never tried."""
    from mcrt.grade.explain.claim import NAMED

    best = next((c.chi2 for c in cands if c.change is not None), None)
    out, readings = [], set()
    for c in cands:
        if c.change is None or (c.explained < NAMED and not c.chi2 - best <= within) or (
                fit is not None and not beats_no_change(c, fit)):
            continue
        if _reading(c.family) not in readings and not c.flexible:  # a flexible fit crowds no cause out
            if len(readings) == TRIED:
                continue  # a further reading waits; a lower-ranked candidate of the tried readings may still be tried
            readings.add(_reading(c.family))
        out.append(c)
        if len(out) == MAX_TRIED:
            break
    return out


def _reading(family: str) -> str:
    """The reading of the image a family belongs to: the camera's families are one."""
    from mcrt.grade.explain.families import CAMERA_FAMILIES

    return "camera" if family in CAMERA_FAMILIES else family


#: Families and catalogued bugs (``catalogue:NAME``) that read the image as one mistake, in other words or as a
#: generalisation of one another: a curve on the values nests a scale, the catalogue's depth off by one is the path
#: depth's 7. Candidates of one reading never make a claim ambiguous (:func:`unconfirmed`).
READINGS = (
    frozenset({"scale", "light_radiance", "colour_matrix", "colour_lost", "channels", "encoding", "tone_curve",
               "sample_clamp", "catalogue:gamma_output"}),  # the values through a function of each pixel's colour
    frozenset({"depth", "catalogue:depth_off_by_one", "catalogue:rr_no_divide", "path_weight"}),
    frozenset({"albedo", "surface_black", "catalogue:albedo_1pct"}),
    frozenset({"reflectance_scale", "reflectance_squared", "catalogue:brdf_no_inv_pi", "catalogue:uniform_as_cosine"}),
    frozenset({"light_sampling", "catalogue:nee_no_area", "catalogue:nee_no_cos_light", "catalogue:nee_no_inv_dist2"}),
    frozenset({"direct_twice", "catalogue:double_count"}),
    frozenset({"light_facing", "catalogue:light_two_sided"}),
    frozenset({"blur", "resampling", "sharpen", "bloom", "catalogue:no_jitter"}),  # filters after rendering
    frozenset({"material", "reflectance", "catalogue:mirror_wrong_sign"}),  # the mirror sphere's material
)
#: A claimed cause must fit better than every adequate candidate of another reading by this many standard deviations
#: of the term-by-term difference of their chi^2 (:func:`closeness` without the BIC's credit): about 2 % one-sided.
CONFIRM_Z = 2.0


def reading_of(c) -> str:
    """The reading of candidate c (:data:`READINGS`; the camera's families are one; else its family or bug)."""
    key = f"catalogue:{c.name}" if c.family == "catalogue" else c.family
    for i, group in enumerate(READINGS):
        if key in group:
            return f"reading {i}"
    return _reading(key)


def unconfirmed(c, adequate: list, fit, named: list) -> list:
    """The adequate candidates of other readings than claimed c's (:data:`READINGS`; not a description nor a flexible
    fit (:attr:`mcrt.grade.candidates.Candidate.flexible`: its fit is no evidence), not a rival,
    not a generalisation of c or nested in it, not ``named`` beside it) that c does not beat by :data:`CONFIRM_Z`
    (:func:`closeness` without the BIC's credit): another cause the image cannot tell from c's, the best of each
    reading. For c a surface out of view (:attr:`mcrt.grade.candidates.Candidate.out_of_view`) every such candidate
    that leaves noise is one: c rests on reflected light alone, so fitting it better confirms nothing."""
    out, seen = [], {reading_of(c)}
    for a in adequate:
        r = reading_of(a)
        if (r in seen or any(a is x for x in named) or a.describes or a.flexible or a.family in c.rivals or c.family in a.rivals
                or c.family in a.generalises or a.family in c.generalises
                or (not c.out_of_view and closeness(fit, c, a, bic=False) >= CONFIRM_Z)):
            continue
        seen.add(r)
        out.append(a)
    return out


def geometry_rival(c, cands: list, fit):
    """The best candidate that changes the same object's geometry as claimed c otherwise (another of
    :data:`mcrt.grade.broader.GEOMETRY`: its size for its place, its place for its size), adequate or not, with a
    smaller chi^2 than c's, that c does not beat by :data:`CONFIRM_Z` (:func:`closeness` without the BIC's credit);
    else None. Such a rival leaves more than noise somewhere, but it fits the image as a whole at least as well: the
    image confirms only that the object's geometry is wrong, not which part of it (a tetrahedron moved reads partly as
    one resized: its outline and shadow shift either way)."""
    obj = broader.geometry_object(c)
    if obj is None:
        return None
    return next((a for a in cands if a is not c and a.family != c.family and a.change is not None
                 and broader.geometry_object(a) == obj and a.chi2 < c.chi2
                 and closeness(fit, c, a, bic=False) < CONFIRM_Z), None)


#: Pixels within this many of one that sees an emitter (directly or in the mirror) are its outline.
OUTLINE = 2


def seen_beyond_emitters(c, fit, sc: Scene2D) -> bool:
    """Whether a change of the whole view (a camera family: :data:`mcrt.grade.explain.families.CAMERA_FAMILIES`)
    fits better than no change away from the emitters' outlines, by :data:`CONFIRM_Z` (the term-by-term statistic of
    :func:`closeness` over those pixels). The light's outline is the image's brightest edge: a warp of a few hundredths
    fits any change of the light's shape there, while a camera that is wrong moves every edge. Other families pass.
    One that fails is not claimed, but stays an adequate reading beside the others (:func:`unconfirmed`)."""
    from scipy.ndimage import binary_dilation

    from mcrt.grade.explain.families import CAMERA_FAMILIES

    if c.family not in CAMERA_FAMILIES or c.change is None:
        return True
    bright = (fit.R @ obj.LUMINANCE) > 1.0  # an emitter seen directly or in the mirror (the lit walls stay below 1)
    away = ~binary_dilation(bright, iterations=OUTLINE)
    h, w, k = fit.D.shape
    gain = (fit.terms(0.0)[: h * w * k] - fit.terms(c.change)[: h * w * k]).reshape(h, w, k)[away & fit.ok.all(axis=-1)]
    spread = float(np.sqrt(np.sum((gain - gain.mean()) ** 2))) if gain.size else 0.0
    return spread > 0 and float(gain.sum()) / spread >= CONFIRM_Z


def claim_rule(S: np.ndarray, R: np.ndarray, mask: np.ndarray, noise: Noise, sc: Scene2D, *, extra_var=None):
    """The adequacy rule as a claim rule of the explanation engine (:class:`mcrt.grade.candidates.ClaimRule`).

    After the share rule (:func:`mcrt.grade.explain.claim.share_rule`), a
    candidate with its share (claimed, or indistinct: a small gain over
    noise's chi-square, as a change confined to one object has) is claimed
    only if its remainder is noise. The best candidates
    (:func:`tried_candidates`: the best of :data:`TRIED` families) are
    tested; of those whose remainder is noise, the **simplest** is claimed
    (:func:`occam`: fewest parameters, unless one with more fits
    significantly better by :func:`closeness`), moved first, with the other
    families that fit as well (:data:`AMBIGUOUS`), unless a candidate of
    another reading fits as well (:func:`unconfirmed`: the verdict is then
    :data:`mcrt.grade.candidates.AMBIGUOUS`, those candidates its
    alternatives, nothing claimed); where that simplest is a
    description (:attr:`mcrt.grade.candidates.Candidate.describes`: any
    monotone curve), it is DESCRIBED, said but not claimed; else the best that is not
    flexible (:attr:`mcrt.grade.candidates.Candidate.flexible`: a parameter per object) is PARTIAL,
    with where its remainder lies, if it explains :data:`PARTIAL_LEAD` of
    the difference and is a cause, not a description (a curve flexible enough
    explains a share of any difference, a camera turned or a light moved, and
    "partly like a tone map" would point the student at a step that is not
    wrong); else nothing is claimed and the difference itself is
    placed on objects (``remainder_where``). ``extra_var(c)`` is the noise
    (H, W, 3) of candidate c's predicted change (None: none). The rule's
    measurements go to ``e.adequacy`` (:class:`Adequacy`).
    """
    from mcrt.grade import candidates as cd
    from mcrt.grade.explain.claim import GAIN_SIGMAS, share_rule

    from mcrt.grade.explain.pixels import directly_lit

    holes = None

    def test(c):
        var = extra_var(c) if extra_var is not None else None
        # A denoiser's kernel is no Gaussian: where the detectors found a filter over the image, the structure a
        # blur leaves on objects is the denoiser's, not another mistake's.
        return remainder_test(S, R, c.change, mask, noise, sc, extra_var=var, explained=c.explained,
                              structure=not (sc.filtered and c.family == "blur"), holes=holes)

    def rule(e, fit, inputs) -> None:
        nonlocal holes
        holes = black_holes(S, R, mask, directly_lit(inputs.basis))
        share_rule(e, fit, inputs)
        tried = {}
        if e.verdict in (cd.CLAIMED, cd.INDISTINCT):  # a share of NAMED; a small gain over noise is no objection
            pool = tried_candidates(e.candidates, GAIN_SIGMAS * math.sqrt(2 * fit.n), fit=fit)
            for c in pool:
                tried[id(c)] = test(c)
            adequate = [c for c in pool if tried[id(c)].verdict == "adequate"]
            # A camera change seen on the emitters' outlines alone is never claimed, but it is still a reading that
            # leaves noise: beside it another claim is unconfirmed (a light moved or a lens warped both fit there).
            # A flexible fit is a last resort: claimed only where nothing else leaves noise.
            c = occam([a for a in adequate if seen_beyond_emitters(a, fit, sc)
                       and not (a.flexible and any(not x.flexible for x in adequate))], fit)
            if c is not None and c.describes:  # only a description leaves noise: how the image differs, no cause
                _claim(e, c, tried[id(c)], [], np.where(mask[..., None], S - R - c.change, 0.0))
                e.verdict = e.adequacy.verdict = cd.DESCRIBED
                if not sc.refitted:  # a curve left after a fitted decoding is no evidence of a step after rendering
                    e.broader = broader.after_rendering(c, S, R, mask, noise.model + noise.reference, sc.labels,
                                                        sc.names)
                return
            if c is not None:
                _claim_simplest(e, c, adequate, tried[id(c)], fit, np.where(mask[..., None], S - R - c.change, 0.0))
                return
        if _partial(e, tried, test, S - R, mask):
            e.broader = (broader.reading(e.best, e.remainder, R, mask, noise.model + noise.reference, sc.labels,
                                         sc.names, e.adequacy.objects, holes=holes, filtered=sc.filtered,
                                         misregistered=sc.misregistered)
                         or _difference_reading(S, R, mask, noise, sc, fit, inputs, holes, extra_var, e.best))
            return
        e.verdict = cd.NONE if e.verdict == cd.CLAIMED else e.verdict
        ad = remainder_test(S, R, 0.0, mask, noise, sc, explained=0.0)
        ad.verdict = "none" if ad.rejected else "adequate"
        e.remainder_where, e.adequacy = ad.where, ad
        if ad.rejected:
            e.broader = _difference_reading(S, R, mask, noise, sc, fit, inputs, holes, extra_var)

    return rule


def _difference_reading(S, R, mask, noise: Noise, sc: Scene2D, fit, inputs, holes, extra_var, lead=None):
    """The bounced light alone changed, or the first surface's direct light alone
    (:func:`mcrt.grade.broader.bounced_light`, :func:`mcrt.grade.broader.direct_light`), tested on the pixels off the
    mirror with the remainder test of :func:`claim_rule` (``extra_var(c)`` a change's own noise, None: none); else the
    difference on the mirror sphere's pixels alone (:func:`mcrt.grade.broader.sphere_alone`; ``lead`` a partial
    reading's lead, None beside none)."""
    from mcrt.grade.candidates import Candidate

    off = mask & ~np.isin(sc.labels, [k for k, n in enumerate(sc.names) if "sphere" in n])

    def verdict(change):
        var = extra_var(Candidate("one_part", "", "", 0.0, change=change)) if extra_var is not None else None
        return remainder_test(S, R, change, off, noise, sc, extra_var=var, holes=holes).verdict

    depths = dict(inputs.basis.nodes.get("depth", []))
    for reading in (broader.bounced_light, broader.direct_light):
        got = reading(fit, R, depths, off, sc.labels, verdict, lambda a, b: closeness(fit, a, b, bic=False) >= CONFIRM_Z,
                      alpha=sc.alpha)
        if got is not None:
            return got
    confined = [n for k, n in enumerate(sc.names) if (mask & (sc.labels == k)).any()
                and remainder_test(S, R, 0.0, mask & (sc.labels != k), noise, sc, holes=holes).verdict == "adequate"]
    return broader.sphere_alone(lead, confined, filtered=sc.filtered, misregistered=sc.misregistered)


def _claim_simplest(e, c, adequate: list, ad: Adequacy, fit, remainder: np.ndarray) -> None:
    """Claim c, the simplest adequate candidate (:func:`claim_rule`; ``ad`` its test, ``remainder`` what it leaves),
    naming beside it the other families that fit as well and its rivals, unless another reading fits as well
    (:func:`unconfirmed`), the cause is a surface out of view, or another change of the same object's geometry fits as
    well or better (:func:`geometry_rival`): then AMBIGUOUS, the last saying the object's geometry."""
    from mcrt.grade import candidates as cd

    alts = [a for a in adequate if a is not c and a.family != c.family
            and a.params <= c.params and a.explained >= c.explained - AMBIGUOUS]
    for fam in c.rivals:  # the best adequate one of each rival family
        a = next((a for a in adequate if a.family == fam and a not in alts), None)
        if a is not None and not any(x.family == fam for x in alts):
            alts.append(a)
    others = unconfirmed(c, adequate, fit, alts)
    rival = None if others else geometry_rival(c, e.candidates, fit)
    _claim(e, c, ad, others or ([rival] if rival else alts), remainder)
    e.adequacy.also_adequate = [(a.family if a.family != "catalogue" else a.name, a.params,
                                 round(closeness(fit, c, a, bic=False), 2)) for a in adequate if a is not c]
    # Another reading fits as well, or the cause is a surface out of view: the image cannot say which (or cannot
    # confirm it), no cause is claimed. Another change of the object's geometry that fits as well leaves the object's
    # geometry, which the words say.
    if others or c.out_of_view or rival:
        e.verdict = e.adequacy.verdict = cd.AMBIGUOUS
    if rival:
        obj = broader.geometry_object(c)
        e.broader = ("object_geometry", f"both point to the {obj}'s geometry: {broader.GEOMETRY_WORDS}")


def _partial(e, tried: dict, test, diff: np.ndarray, mask: np.ndarray) -> bool:
    """Make e a partial reading, led by its best candidate that is not flexible (a flexible fit's share is no
    evidence of its cause), where that one is a cause (not a description), explains :data:`PARTIAL_LEAD` of the
    difference ``diff`` (S - R; ``mask`` the pixels used) and leaves structure (``test``, or its result in
    ``tried``); whether it did."""
    from mcrt.grade import candidates as cd

    lead = next((c for c in e.candidates if not c.flexible), None)
    if lead is None or lead.change is None or lead.explained < PARTIAL_LEAD or lead.describes:
        return False
    ad = tried.get(id(lead)) or test(lead)
    if ad.verdict != "partial":
        return False
    if lead is not e.best:
        e.candidates = [lead] + [x for x in e.candidates if x is not lead]
        e.remainder = np.where(mask[..., None], diff - lead.change, 0.0)
    e.verdict, e.remainder_where, e.adequacy = cd.PARTIAL, ad.where, ad
    return True


def _claim(e, c, ad: Adequacy, alternatives: list, remainder: np.ndarray) -> None:
    """Claim candidate c of explanation e (first in its list, ``remainder`` its own), naming the alternatives."""
    from mcrt.grade import candidates as cd

    if c is not e.best:
        e.remainder = remainder
        e.candidates = [c] + [x for x in e.candidates if x is not c]
    ad.alternatives = [(a.family, a.text, a.explained) for a in alternatives]
    e.verdict, e.adequacy = cd.CLAIMED, ad

