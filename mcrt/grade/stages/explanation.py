"""Explanation: which mistake explains a failing image, in the student's terms.

Every family of :mod:`mcrt.grade.explain` (the catalogued bugs among them)
is fitted to the image by the engine, and the claim rule :data:`CLAIM_RULE`
decides what the feedback may claim: a cause only when what it leaves is
noise (:mod:`mcrt.grade.adequacy`). Without the engine's renders (a
context prepared without them, another camera) the catalogue is ranked by
tile statistics alone. Excess noise on unbiased tiles is told apart from a
deterministic error by ranking the catalogue at pixel level, by its noise
pattern and by its amount of noise.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import AMBIGUOUS, Inputs
from mcrt.grade.explain.catalogue import (catalogue_power, excess_fits, excess_where, rank_mutants, rank_noise,
                                         rank_noise_level)
from mcrt.grade.adequacy import Scene2D, claim_rule
from mcrt.grade.regions import change_region, rel_lum, short_text, signature_region, tile_means
from mcrt.grade.stages.state import Grading, Hand, Level
from mcrt.stats.onesample import Noise, multiscale_test, scale_stats

#: Makes the rule that decides whether the best explanation is claimed (mcrt.grade.candidates.ClaimRule): the
#: share rule, then the remainder tested with the bias test's noise model (mcrt.grade.adequacy.claim_rule).
CLAIM_RULE = claim_rule


def _change_var(g: Grading, c, basis, noise: Noise, R: np.ndarray) -> np.ndarray:
    """The noise of a candidate's predicted change: its expected images' (a catalogued bug) or the basis renders',
    with what a curve on the values adds to the hand-in's noise (:attr:`Candidate.noise`) where it grows it; for a gain (:attr:`mcrt.grade.candidates.Candidate.gain`) the basis renders' grown with the factor it puts on
    them, (M / R - 1)^2 times theirs where that is more than 1 (M the model image), and the hand-in's own noise grown
    with it, a correct render's times (M / R)^2 - 1 where M is brighter than R."""
    if c.catalogue and c.name in g.ctx.mutants:
        m, b = g.ctx.mutants[c.name], g.ctx.baseline
        return m.var.astype(np.float64) / m.spp + b.var.astype(np.float64) / b.spp
    var = basis.var.astype(np.float64) / basis.spp
    if c.noise is not None:  # a curve on the values: the hand-in's noise bent with it
        var = var + np.maximum(c.noise - np.asarray(noise.model, np.float64), 0.0)
    if c.gain and c.change is not None:
        ratio = np.where(R > 0, (R + c.change) / np.where(R > 0, R, 1.0), 1.0)
        var = (var * np.maximum((ratio - 1.0) ** 2, 1.0)
               + np.asarray(noise.model, np.float64) * np.maximum(ratio**2 - 1.0, 0.0))
    return var


def _tile_means(x, mask, tile):
    return tile_means(np.asarray(x, np.float64), mask, tile)


def diagnose(g: Grading, hand: Hand, noise: Noise, *, pixel_level: bool = False) -> list:
    """Rank the catalogue against the image as handed in (after flips only), then explain it (tile level).

    Tile-level by default (the bias test's first scale and its noise);
    ``pixel_level`` compares single pixels with the model noise alone,
    for deviations that cancel within tiles (aliasing: no pixel jitter).
    """
    ctx, cam, mask, R, tile = g.ctx, hand.cam, hand.mask, hand.R, hand.base_tile
    if cam != g.a.camera or not ctx.mutants:
        g.notes.append("no bug diagnosis: the catalogue's images exist for the assigned camera only")
        return []
    d = hand.diag_imgs
    img = d[0] if len(d) == 1 else 0.5 * (d[0] + d[1])
    resid = np.where(mask[..., None], img - R, 0.0)
    unit = 1 if pixel_level else tile
    s = scale_stats(resid, R, mask, noise, unit, min_n=1 if pixel_level else 2)
    labels, names, direct = ctx.labels[cam], ctx.label_names, ctx.direct_fraction[cam]
    r_t = _tile_means(R, mask, tile)

    def signature(name):
        return rel_lum(_tile_means(ctx.mutants[name].mean - ctx.baseline.mean, mask, tile), r_t)

    def where_fn(name):
        return signature_region(signature(name), R.shape[:2], tile, labels, names, direct, g.th.min_effect)

    cands, chi0 = rank_mutants(s.diff, s.var, s.ref, s.valid, ctx.mutants, ctx.baseline, mask, unit,
                               ctx.mutant_texts, where_fn)
    g.details["diagnosis"] = {"level": "pixel" if pixel_level else f"{tile}x{tile} tiles", "chi2_none": chi0,
                              "terms": int(np.count_nonzero(s.valid)) * 3}
    g.chi0 = chi0
    g.diagnosis = [c.to_dict() for c in cands[:5]]
    g.figures["mutant_rel_tiles"] = signature(cands[0].name)
    g.figures["mutant_name"] = cands[0].name
    if not pixel_level:
        explain(g, hand, img, mask, noise)
    return cands[:2]


def explain(g: Grading, hand: Hand, img, mask, noise: Noise):
    """Fit the families of :mod:`mcrt.grade.explain` to the image; None without the engine's renders.

    When the claim rule claims no cause the diagnosis is left empty: no bug is named. Where causes of several
    readings fit as well (AMBIGUOUS) they are the diagnosis, as the closest, none claimed.
    """
    from mcrt.grade.explain import explain as engine
    from mcrt.grade.objects import baseline_shares

    ctx, cam, R, tile = g.ctx, hand.cam, hand.R, hand.base_tile
    basis = getattr(ctx, "explain", None)
    if basis is None or cam != basis.camera or basis.base.shape != R.shape:
        return None
    labels, names, direct = ctx.labels[cam], ctx.label_names, ctx.direct_fraction[cam]
    th, a = g.th, g.a

    def where_fn(dm):
        return change_region(dm, R, mask, tile, labels, names, direct, th.min_effect)

    def test_remainder(resid):
        return multiscale_test(resid, R, mask, noise, a.tiles, alpha=th.alpha, min_effect=th.min_effect,
                               full_effect=th.full_effect)

    inputs = Inputs(basis, mutants=ctx.mutants, baseline=ctx.baseline, texts=ctx.mutant_texts, labels=labels,
                    label_names=names, where=where_fn, test_remainder=test_remainder)
    penalised = g.details.get("structure", {}).get("penalised", {})
    sc = Scene2D(tuple(a.tiles), th.alpha, th.min_effect, th.full_effect, labels, names,
                 shares=baseline_shares(ctx, cam, R, hand.ref, mask,
                                        unsampled=bool(g.details.get("noise", {}).get("unsampled"))),
                 filtered=any(penalised.get(k, 0) for k in ("blur", "correlation")),
                 misregistered=bool(penalised.get("registration", 0)),
                 # Decoded with a curve fitted to it, not its declared one: a curve left after that decoding is no
                 # evidence of a step after rendering, as the decoding is none where nothing is claimed
                 # (calibration.judge_encoding).
                 refitted="linear" in hand.corrected)
    rule = CLAIM_RULE(img, R, mask, noise, sc, extra_var=lambda c: _change_var(g, c, basis, noise, R))
    e = engine(img, R, noise.model + noise.reference, mask, inputs, claim=rule, tile=tile)
    g.explanation = e
    g.details["explanation"] = e.to_dict()
    if e.adequacy is not None and e.adequacy.map is not None:
        g.figures["objects_rel"] = e.adequacy.map
    if e.named is not None:
        g.diagnosis = [c.to_dict() for c in e.candidates[:5]]
        g.figures["mutant_rel_tiles"] = rel_lum(_tile_means(e.named.change, mask, tile), _tile_means(R, mask, tile))
        g.figures["mutant_name"] = e.named.name
    else:
        said = {(f, t) for f, t, _ in e.adequacy.alternatives} if e.verdict == AMBIGUOUS else set()
        g.diagnosis = [c.to_dict() for c in e.candidates if said and (c is e.best or (c.family, c.text) in said)][:5]
        g.figures.pop("mutant_rel_tiles", None)
        g.figures.pop("mutant_name", None)
    return e


def explain_excess_noise(g: Grading, hand: Hand, lvl: Level) -> str:
    """What the catalogue says of too much noise on unbiased tiles: more words for the ``noise`` verdict."""
    diag = diagnose(g, hand, lvl.noise, pixel_level=True)
    nd = _rank_noise(g, hand, lvl)
    if _conclusive_chi2(diag, g.chi0 if diag else 0.0, g.details.get("diagnosis", {}).get("terms", 0)):
        g.headline = f"Deviations that cancel within tiles: consistent with {short_text(diag[0].text)}."
        return (f". The excess is not random: pixel by pixel it matches {short_text(diag[0].text)} "
                f"({diag[0].name}), which removes {100 * diag[0].explained:.0f} % of the mismatch (the rest is noise)")
    if _conclusive(nd):
        g.headline = f"Too noisy in a telling pattern: consistent with {short_text(nd[0].text)}."
        g.diagnosis = [c.to_dict() for c in nd[:5]]
        g.details["diagnosis"] = {"level": "noise pattern"}
        g.figures.pop("mutant_rel_tiles", None)
        return (f". Where the noise is, matches {short_text(nd[0].text)} ({nd[0].name}) better than a correct "
                f"renderer (it explains {100 * nd[0].explained:.0f} % of the mismatch)")
    var_nominal = lvl.model_ps / (lvl.spp_nominal * lvl.per) + lvl.ref_noise + lvl.q
    lv = _rank_noise_level(g, hand, lvl, var_nominal)
    if _conclusive(lv):
        g.headline = f"Right mean, far too much noise: consistent with {short_text(lv[0].text)}."
        g.diagnosis = [dict(c.to_dict(), amplitude=None, variance_inflation=c.amplitude) for c in lv[:5]]
        g.details["diagnosis"] = {"level": "noise level"}
        g.figures.pop("mutant_rel_tiles", None)
        return (f". The mean is right but the noise is not: {short_text(lv[0].text)} ({lv[0].name}) multiplies "
                f"the variance by about {lv[0].amplitude:.0f} with rare, very bright samples and leaves the mean "
                f"nearly unchanged")
    g.diagnosis = []
    g.figures.pop("mutant_rel_tiles", None)
    return ""


def _rank_noise(g: Grading, hand: Hand, lvl: Level) -> list:
    """Rank the catalogue by its noise pattern (:func:`mcrt.grade.explain.catalogue.rank_noise`)."""
    ctx, mask, R, tile, noise = g.ctx, hand.mask, hand.R, hand.base_tile, lvl.noise
    if hand.cam != g.a.camera or not ctx.mutants:
        return []
    s = scale_stats(lvl.resid, R, mask, noise, tile)
    n3 = np.maximum(s.n, 1.0)[..., None]
    ref_share = _tile_means(noise.reference, mask, tile)
    spread = np.maximum(s.var_spread * n3 - ref_share, 0.0)
    cands, _ = rank_noise(spread, s.n, s.valid, s.ref + s.diff, ctx.mutants, ctx.baseline, mask, tile, lvl.samples,
                          ctx.mutant_texts)
    return cands[:2]


def _rank_noise_level(g: Grading, hand: Hand, lvl: Level, var_nominal) -> list:
    """Rank the catalogue by the amount of noise (:func:`mcrt.grade.explain.catalogue.rank_noise_level`), among
    the bugs whose mean bias would not show at this noise.

    Only for noise in rare outliers, where most pixels keep the noise of
    the declared spp. The measure is the median pixel's squared residual
    against mcrt's variance at the nominal spp (``var_nominal``), over the
    median of a chi-square with one degree of freedom (``bulk``). A bug
    is named only if ``bulk`` stays below var_ratio^(1/4) and below half
    of what a correct renderer with the image's effective sample count
    gives: a correct mcrt render at that count (at most 64 spp, scaled) is
    made and measured the same way. Too few samples raise the median
    pixel's residual with the whole noise, though less than the variance
    when a pixel's samples are heavy-tailed, by an amount that depends on
    the scene: hence a simulated render, not a formula.
    """
    from mcrt.grade.expected import grading_settings
    from mcrt.render import render

    ctx, mask, R, samples, var_ratio = g.ctx, hand.mask, hand.R, lvl.samples, lvl.var_ratio
    if not ctx.mutants or not np.isfinite(var_ratio) or var_ratio <= 1.0:
        return []

    def bulk_of(r):
        with np.errstate(divide="ignore", invalid="ignore"):
            z2 = r**2 / var_nominal
        z2 = z2[mask[..., None].repeat(3, axis=2) & np.isfinite(z2)]
        return float(np.median(z2)) / 0.4549 if z2.size else np.inf  # 0.4549: median of chi-square(1)

    bulk = bulk_of(lvl.resid)
    details = g.details.setdefault("noise", {})
    details["bulk_ratio"] = bulk
    if not bulk < var_ratio**0.25:
        return []
    a = g.a
    n_sim = int(min(max(round(samples), 1), 64))
    scene = a.load_scene()
    sim = render(scene, grading_settings(scene, hand.cam, R.shape[1], R.shape[0], a.max_depth, n_sim, a.seed + 3),
                 progress=False)
    bulk_few = bulk_of(np.where(mask[..., None], sim.mean.astype(np.float64) - R, 0.0)) * n_sim / max(samples, 1e-9)
    details["bulk_ratio_fewer_samples"] = bulk_few
    if not bulk < 0.5 * bulk_few:
        return []
    # Most pixels are quieter than fewer samples would leave them: the excess is in a few (the noise criterion's
    # words say so, not fewer samples), and a bug is named by it only where its own excess lies.
    details["excess_in_few_pixels"] = True
    hidden = {p["mutant"] for p in catalogue_power(ctx, samples) if not p["detectable"]}
    labels, n = ctx.labels[hand.cam], len(ctx.label_names) - 1
    fits = {m for m in hidden if excess_fits(excess_where(ctx.mutants[m], ctx.baseline, mask, labels, n),
                                             lvl.resid, var_nominal, mask, labels)}
    return rank_noise_level(var_ratio, ctx.mutants, ctx.baseline, mask, ctx.mutant_texts, fits)[:2]


def _conclusive_chi2(cands, chi0: float, terms: int) -> bool:
    r"""Pixel-level ranking: the best mutant lowers chi^2 by far more than noise could (5 sd of a chi^2
    with ``terms`` degrees of freedom) and three times as much as the next one, and it beats a correct
    renderer with fewer samples than declared.

    That last rival has the model's noise times a factor s, fitted to the
    image (s = chi0 / terms); in Gaussian deviance, -2 ln L + const, it scores
    :math:`chi0 / s + terms \ln s = terms (1 + \ln(chi0 / terms))` against
    the mutant's chi^2 at the declared noise. A correct render with a
    sixteenth of its declared samples has chi0 near 16 terms: a mutant that
    removes a few per cent of that is not a diagnosis.
    """
    if not cands or terms <= 0:
        return False
    gain1 = chi0 - cands[0].chi2
    gain2 = chi0 - cands[1].chi2 if len(cands) > 1 else 0.0
    fewer_samples = terms * (1.0 + np.log(max(chi0 / terms, 1.0)))
    return gain1 > 5.0 * np.sqrt(2.0 * terms) and gain1 > 3.0 * max(gain2, 0.0) and cands[0].chi2 < fewer_samples


def _conclusive(cands) -> bool:
    """The best candidate explains at least 30 % and twice as much as the next one."""
    return bool(cands) and cands[0].explained >= 0.3 and (len(cands) < 2 or cands[0].explained >= 2 * max(cands[1].explained, 0.0))
