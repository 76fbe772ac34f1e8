r"""The bug catalogue as candidates: fitted among the families, and ranked by tiles, pixels or noise.

Each mutant m of :data:`mcrt.mutants.MUTANTS` has an expected image E_m,
rendered once by mcrt with the same seed as the bug-free baseline E_0 (see
:mod:`mcrt.grade.expected`), so the bug's signature
:math:`\Delta_m = E_m - E_0` is nearly free of noise. With the student's
tile differences :math:`D_t = \bar S_t - \bar R_t` and their variances V_t
from the bias test (first scale, all channels),

.. math::

    \chi^2_m(a) = \sum_t \frac{(D_t - a\,\Delta_{m,t})^2}{V_t + W_{m,t} + (f \bar R_t)^2},
    \qquad \chi^2_0 = \sum_t \frac{D_t^2}{V_t + (f \bar R_t)^2},

where W is the variance of the signature's tile mean and f = 0.2 % a floor
for what no render reproduces exactly. Mutants are ranked by
:math:`\chi^2_m(1)`, the bug exactly as catalogued; the best-fitting
amplitude :math:`\hat a \in [0, 4]` is reported too ("the same pattern at
half the strength" points to a variant of the bug). The share of the
excess chi-square a mutant removes, :math:`1 - \chi^2_m(1)/\chi^2_0`, is
reported as how much of the difference it explains (:func:`rank_mutants`: by
tiles, or by single pixels for deviations that cancel within tiles).

Among the families of the engine (:func:`catalogue`), each bug predicts the
change :math:`\Delta_m` at full resolution and is scored like any family.
Bugs that mostly add variance are ranked by their noise instead: its
pattern (:func:`rank_noise`) or its amount (:func:`rank_noise_level`).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import FLOOR, Candidate
from mcrt.grade.explain.mirror import NORMALS_ALIKE
from mcrt.grade.regions import short_text, tile_means, valid_counts
from mcrt.stats.onesample import bias_scales
from mcrt.stats.tiles import tile_counts, tile_sums


#: Bugs whose image another mistake of a student's program makes alike, worded beside the bug's own words: the
#: catalogue names a line of code, and the image cannot tell it from these. (A mirror whose reflection points into
#: the sphere turns it black; a sphere of glass or of a dark diffuse material reflects little too, and at a student's
#: noise the difference is the few per cent they still reflect; a mirror reflecting about wrong normals, or a mesh that
#: is not the sphere, turns it dark as well.)
LOOK_ALIKES = {"mirror_wrong_sign": "or the sphere given another material that reflects little (glass, or a dark "
                                    f"diffuse one), which leaves it nearly black too, {NORMALS_ALIKE}"}


def catalogue(fit, inputs) -> list[Candidate]:
    """Every catalogued bug as a candidate with the change its expected image makes (no parameter), with its
    look-alikes' words (:data:`LOOK_ALIKES`)."""
    out = []
    if not inputs.mutants:
        return out
    base = inputs.baseline.mean.astype(np.float64)
    for name, e in inputs.mutants.items():
        dm = e.mean.astype(np.float64) - base
        text = short_text(inputs.texts.get(name, name)) + (f", {LOOK_ALIKES[name]}" if name in LOOK_ALIKES else "")
        out.append(Candidate("catalogue", name, text, fit.delta(dm), 0, catalogue=True, change=dm))
    return out


catalogue.name = "catalogue"


def _ranked(name: str, texts: dict, chi2: float, chi2_fit: float, amplitude: float, explained: float) -> Candidate:
    return Candidate("catalogue", name, texts.get(name, name), chi2, explained=explained, catalogue=True,
                     amplitude=amplitude, chi2_fit=chi2_fit, ranked=True)


def rank_mutants(diff: np.ndarray, var: np.ndarray, ref_t: np.ndarray, valid: np.ndarray, mutants: dict,
                 baseline, mask: np.ndarray, tile: int, texts: dict, where_fn=None) -> tuple[list[Candidate], float]:
    """Candidates sorted best first, and chi^2 of 'no bug' (see the module docstring).

    ``mutants`` maps names to :class:`~mcrt.grade.expected.Expected` images
    at the grade resolution; ``baseline`` is the bug-free one of the same seed.
    ``where_fn(name)`` describes where a mutant's signature lies (for the
    best five candidates only).
    """
    ok = valid[..., None] & np.isfinite(diff) & np.isfinite(var)
    floor = (FLOOR * np.abs(ref_t)) ** 2
    v0 = np.where(ok, var + floor, 1.0)
    v0 = np.where(v0 > 0, v0, 1e-30)
    chi0 = float(np.sum(np.where(ok, diff**2 / v0, 0.0)))
    n_pix = valid_counts(mask, tile)
    base_t = tile_means(baseline.mean.astype(np.float64), mask, tile)
    out = []
    for name, e in mutants.items():
        delta = tile_means(e.mean.astype(np.float64), mask, tile) - base_t
        wv = (tile_sums(np.where(mask[..., None], e.var / e.spp + baseline.var / baseline.spp, 0.0), tile) / n_pix**2)
        w = np.where(ok, var + wv + floor, 1.0)
        w = np.where(w > 0, w, 1e-30)
        chi1 = float(np.sum(np.where(ok, (diff - delta) ** 2 / w, 0.0)))
        num = float(np.sum(np.where(ok, diff * delta / w, 0.0)))
        den = float(np.sum(np.where(ok, delta * delta / w, 0.0)))
        a = float(np.clip(num / den, 0.0, 4.0)) if den > 0 else 0.0
        chia = float(np.sum(np.where(ok, (diff - a * delta) ** 2 / w, 0.0)))
        out.append(_ranked(name, texts, chi1, chia, a, 1.0 - chi1 / chi0 if chi0 > 0 else 0.0))
    out.sort(key=lambda c: c.chi2)
    if where_fn is not None:
        for c in out[:5]:
            c.where = where_fn(c.name)
    return out, chi0



def rank_noise(spread: np.ndarray, n: np.ndarray, valid: np.ndarray, image_t: np.ndarray, mutants: dict, baseline,
               mask: np.ndarray, tile: int, samples: float, texts: dict) -> tuple[list[Candidate], float]:
    r"""Candidates ranked by how well their *noise* matches the image's (for bugs that mostly add variance).

    A bug can leave the mean nearly right and change the variance a lot (a
    light emitting from both sides 1 cm under the ceiling: a 1/d^2
    singularity). Per tile and channel, the image's measured relative pixel
    variance :math:`S^2_t / \bar S_t^2` (``spread`` over the squared tile
    mean ``image_t``) is compared with the relative variance each mutant
    predicts at the student's sample count,
    :math:`v_{m,t} = \overline{\sigma^2_m}_t / (samples\, \bar E_{m,t}^2)`,
    by the deviance of a variance, :math:`\sum_t r - 1 - \ln r` with
    :math:`r = (S^2_t/\bar S_t^2) / v_{m,t}` (0 for a perfect match, growing
    with the log-ratio either way). Relative, so that a bug that only
    brightens the image does not pass for a noisy one. The share explained is
    ``1 - deviance_m / deviance_none``.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        meas = spread / np.where(image_t > 0, image_t, np.nan) ** 2
    ok = valid[..., None] & (n[..., None] >= 8) & np.isfinite(meas) & (meas > 0)

    def deviance(e) -> float:
        m = tile_means(e.mean.astype(np.float64), mask, tile)
        v = tile_means(e.var.astype(np.float64), mask, tile) / samples
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = v / m**2
        good = ok & np.isfinite(rel) & (rel > 0)
        r = np.where(good, meas / np.where(good, rel, 1.0), 1.0)
        # A tile the mutant predicts no noise for, but that has noise, counts as a large mismatch.
        bad = ok & ~good
        return float(np.sum(np.where(good, r - 1.0 - np.log(np.maximum(r, 1e-300)), 0.0)) + 50.0 * np.count_nonzero(bad))

    d0 = deviance(baseline)
    out = []
    for name, e in mutants.items():
        dm = deviance(e)
        out.append(_ranked(name, texts, dm, dm, 1.0, 1.0 - dm / d0 if d0 > 0 else 0.0))
    out.sort(key=lambda c: c.chi2)
    return out, d0



def variance_inflation(e, baseline, mask: np.ndarray) -> float:
    """How many times a bug multiplies the image's relative variance: (sum var / sum mean^2) against the baseline's."""
    def rel(x) -> float:
        m, v = x.mean.astype(np.float64)[mask], x.var.astype(np.float64)[mask]
        return float(np.sum(v) / max(np.sum(m * m), 1e-300))

    return rel(e) / max(rel(baseline), 1e-300)


#: The share of a bug's excess variance the surfaces it is found on hold (:func:`excess_where`).
EXCESS_HELD = 0.9
#: The least share of an image's excess variance that must lie there for the bug to be named by its noise.
EXCESS_THERE = 0.5


def excess_where(e, baseline, mask: np.ndarray, labels: np.ndarray, n_labels: int) -> np.ndarray:
    """(n_labels,) bool: the fewest surfaces that hold :data:`EXCESS_HELD` of the variance a bug adds to the
    baseline's (its catalogue image ``e``): where its rare, huge samples land (a light emitting from both sides: the
    ceiling around it)."""
    add = np.maximum(e.var.astype(np.float64) - baseline.var.astype(np.float64), 0.0).sum(axis=-1)
    per = np.bincount(np.where(mask, labels, n_labels).ravel(), add.ravel(), minlength=n_labels + 1)[:n_labels]
    out = np.zeros(n_labels, bool)
    if per.sum() <= 0:
        return out
    order = np.argsort(-per)
    held = np.cumsum(per[order]) / per.sum()
    out[order[:int(np.searchsorted(held, EXCESS_HELD)) + 1]] = True
    return out


def excess_fits(where: np.ndarray, resid: np.ndarray, var: np.ndarray, mask: np.ndarray, labels: np.ndarray) -> bool:
    """Whether an image's excess (its squared residual beyond the variance ``var`` at its declared spp, summed per
    surface) lies :data:`EXCESS_THERE` or more on the surfaces ``where`` of :func:`excess_where`: a bug named by the
    amount of its noise must also put it where its noise is."""
    n = len(where)
    ex = np.where(mask[..., None], resid**2 - var, 0.0).sum(axis=-1)
    per = np.maximum(np.bincount(np.where(mask, labels, n).ravel(), ex.ravel(), minlength=n + 1)[:n], 0.0)
    return bool(per.sum() > 0 and per[where].sum() >= EXCESS_THERE * per.sum())


def rank_noise_level(var_ratio: float, mutants: dict, baseline, mask: np.ndarray, texts: dict,
                     hidden: set[str]) -> list[Candidate]:
    r"""Candidates for an image with a right mean and far too much noise, by the *amount* of noise.

    Some bugs leave the mean almost right and multiply the variance by a
    large factor through rare, huge samples (a light emitting from both
    sides 1 cm under the ceiling: a 1/d^2 singularity). Their noise is too
    heavy-tailed for a tile-by-tile pattern (:func:`rank_noise`): most tiles
    of a render hold no outlier. The image-wide factor is steadier: each
    mutant's inflation :math:`I_m` (:func:`variance_inflation`, from its
    catalogue image) is compared with the image's measured ratio ``var_ratio``
    by :math:`|\ln(\mathrm{var\_ratio} / I_m)|`; the share explained is
    :math:`1 - |\ln(\mathrm{var\_ratio}/I_m)| / \ln \mathrm{var\_ratio}`. Only
    the mutants in ``hidden`` compete: those whose mean bias the bias test
    could not have seen at the image's noise (it passed that test).
    """
    if not var_ratio > 1.0:
        return []
    out = []
    for name in hidden:
        infl = variance_inflation(mutants[name], baseline, mask)
        dist = abs(np.log(var_ratio / infl)) if infl > 0 else np.inf
        out.append(_ranked(name, texts, float(dist), float(dist), float(infl), float(1.0 - dist / np.log(var_ratio))))
    out.sort(key=lambda c: c.chi2)
    return out



def catalogue_power(ctx, spp: float | None = None) -> list[dict]:
    r"""Which catalogued bugs the bias test can see at ``spp`` (default: the assignment's).

    For each mutant and each tile of each scale, the expected statistic of a
    render with the bug, :math:`z = \Delta_t / \sqrt{V_t}`, with
    :math:`V_t` mcrt's variance at ``spp`` plus the reference's, and the
    signature :math:`\Delta_t` shrunk by two of its own standard deviations
    (it is estimated from the catalogue's renders), counted only where the
    relative effect reaches ``min_effect``. ``z_max`` against Holm's first
    threshold ``z_crit``
    (two-sided, over all tests) says whether the bug shows in a typical
    render (``detectable``: z_max >= z_crit + 1, about 84 % power at the best
    tile); ``spp_needed`` is the sample count for that, ``None`` (with the
    reason in ``limit``) when the reference's noise forbids it or the effect
    is too small to estimate from the catalogue's renders. Deviations that cancel within tiles
    (no pixel jitter) show in the noise criterion instead.
    """
    from scipy import stats as sps

    a = ctx.assignment
    spp = float(spp or a.spp)
    cam = a.camera
    ref = ctx.references[cam]
    model = ctx.model_var[cam].astype(np.float64)
    h, w = ref.mean.shape[:2]
    tiles = bias_scales(a.tiles, h, w)
    n_tests = sum(3 * tile_counts(h, w, t).size for t in tiles)
    zcrit = float(sps.norm.isf(a.thresholds.alpha / (2 * max(n_tests, 1))))
    out = []
    for name, e in ctx.mutants.items():
        best, best_fixed = 0.0, 0.0
        for t in tiles:
            n = tile_counts(h, w, t)[..., None]
            d = (tile_sums(e.mean.astype(np.float64) - ctx.baseline.mean, t)) / n
            r = tile_sums(ref.mean.astype(np.float64), t) / n
            v_student = tile_sums(model, t) / n**2 / spp
            v_fixed = tile_sums(ref.var / ref.spp, t) / n**2
            # The signature is an estimate: shrink it by two of its own standard deviations (without the
            # common-random-number correlation, so this is cautious).
            sd_sig = np.sqrt(tile_sums(e.var / e.spp + ctx.baseline.var / ctx.baseline.spp, t)) / n
            d = np.sign(d) * np.maximum(np.abs(d) - 2.0 * sd_sig, 0.0)
            rel = np.abs(d) / np.maximum(np.abs(r), 1e-12)
            ok = rel >= a.thresholds.min_effect
            if not ok.any():
                continue
            z = np.where(ok, np.abs(d) / np.sqrt(v_student + v_fixed), 0.0)
            i = np.unravel_index(int(np.argmax(z)), z.shape)
            if z[i] > best:
                best = float(z[i])
                # samples for z = zcrit + 1 at this tile: d^2 / (v_s spp / s + v_f) = (zcrit + 1)^2
                need = (zcrit + 1.0) ** 2
                vs1, vf = float(v_student[i] * spp), float(v_fixed[i])
                denom = float(d[i]) ** 2 / need - vf
                best_fixed = float(vs1 / denom) if denom > 0 else float("inf")
        if best <= 0:
            need, limit = None, "effect within the catalogue's own noise"
        elif not np.isfinite(best_fixed):
            need, limit = None, "reference too noisy"
        else:
            need, limit = max(1, int(np.ceil(best_fixed))), None
        out.append({"mutant": name, "z_max": best, "z_crit": zcrit, "detectable": best >= zcrit + 1.0,
                    "spp_needed": need, "limit": limit})
    return out
