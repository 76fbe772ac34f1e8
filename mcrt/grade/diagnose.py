r"""Which catalogued bug does a failing image most resemble, and where is it wrong?

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
reported as how much of the difference it explains.

Regions are described by the surfaces the camera sees there (the walls by
their colour, the floor, the ceiling, the sphere...) and by the share of
direct light, so that the words match what a student sees in the image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcrt.grade.score import LUMINANCE, bias_scales
from mcrt.stats.tiles import tile_box, tile_counts, tile_sums

FLOOR = 0.002


@dataclass
class Candidate:
    name: str
    text: str
    chi2: float  # at amplitude 1
    chi2_fit: float  # at the best amplitude
    amplitude: float
    explained: float  # 1 - chi2 / chi2_none
    where: str  # where this bug changes the image (from its expected image)

    def to_dict(self) -> dict:
        return {"mutant": self.name, "description": self.text, "chi2": self.chi2, "chi2_best_amplitude": self.chi2_fit,
                "amplitude": self.amplitude, "explained": self.explained, "where": self.where}


_PROPER = ("Russian", "Lambertian", "Monte")


def short_text(text: str) -> str:
    """The first clause of a catalogue entry, to follow 'consistent with': 'Russian roulette without dividing by
    the survival probability', 'next-event estimation without the cosine at the light'."""
    s = text.split(": ")[0].split(". ")[0].rstrip(".")
    if len(s) > 1 and s[1].islower() and not s.startswith(_PROPER):
        s = s[0].lower() + s[1:]
    return s


def tile_means(x: np.ndarray, mask: np.ndarray, tile: int) -> np.ndarray:
    """Means of an (H, W, 3) array over the valid pixels (``mask``) of each tile (0 where a tile has none)."""
    return tile_sums(np.where(mask[..., None], x, 0.0), tile) / _valid_counts(mask, tile)


def _valid_counts(mask: np.ndarray, tile: int) -> np.ndarray:
    """Valid pixels per tile, at least 1, shape (tiles_y, tiles_x, 1)."""
    return np.maximum(tile_sums(mask.astype(np.float64), tile), 1.0)[..., None]


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
    n_pix = _valid_counts(mask, tile)
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
        out.append(Candidate(name, texts.get(name, name), chi1, chia, a, 1.0 - chi1 / chi0 if chi0 > 0 else 0.0, ""))
    out.sort(key=lambda c: c.chi2)
    if where_fn is not None:
        for c in out[:5]:
            c.where = where_fn(c.name)
    return out, chi0


def rel_lum(d: np.ndarray, ref_t: np.ndarray) -> np.ndarray:
    """Relative luminance difference d / |ref| per tile (0 where the reference is black)."""
    dl, rl = d @ LUMINANCE, ref_t @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(rl) > 1e-12, dl / np.abs(rl), 0.0)


def _join(items: list[str]) -> str:
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def describe_tiles(rel: np.ndarray, chosen: np.ndarray, shape: tuple[int, int], tile: int, labels: np.ndarray,
                   names: tuple[str, ...], direct: np.ndarray) -> str:
    """Words for the tiles marked in ``chosen`` (tiles_y, tiles_x), with signed relative effects ``rel``.

    For example: 'too dark (about -38 %) on the floor, wall AB (red) and the ceiling, where
    indirect light dominates (70 % of the light there is indirect); too bright
    (about +12 %) on the mirror sphere'.
    """
    h, w = shape
    parts = []
    for sign, word in ((-1, "too dark"), (1, "too bright")):
        sel = chosen & (np.sign(rel) == sign)
        if not sel.any():
            continue
        weights = np.zeros(len(names))
        eff, npx, dsum, wsum = 0.0, 0, 0.0, 0.0
        for ty, tx in zip(*np.nonzero(sel)):
            y0, y1, x0, x1 = tile_box(h, w, tile, int(ty), int(tx))
            lab = labels[y0:y1, x0:x1].ravel()
            a = abs(float(rel[ty, tx]))
            np.add.at(weights, lab, a)
            eff += float(rel[ty, tx]) * lab.size
            npx += lab.size
            dsum += a * float(direct[y0:y1, x0:x1].sum())
            wsum += a * lab.size
        order = np.argsort(-weights)
        total = weights.sum()
        where = [names[i] for i in order[:3] if weights[i] >= 0.15 * total and names[i] != "nothing"]
        if not where:
            where = [names[order[0]]]
        text = f"{word} (about {100 * eff / max(npx, 1):+.0f} %) on {_join(where)}"
        share = dsum / wsum if wsum > 0 else 1.0
        if share < 0.45:
            text += f", where indirect light dominates ({100 * (1 - share):.0f} % of the light there is indirect)"
        elif share > 0.8:
            text += ", where direct light dominates"
        parts.append(text)
    return "; ".join(parts)


def signature_region(rel: np.ndarray, shape, tile, labels, names, direct, min_effect: float) -> str:
    """Where a bug's expected signature (relative luminance per tile) is strong."""
    mx = float(np.max(np.abs(rel))) if rel.size else 0.0
    if mx < min_effect:
        return "no visible change at this resolution"
    chosen = np.abs(rel) >= max(0.3 * mx, min_effect)
    return describe_tiles(rel, chosen, shape, tile, labels, names, direct)


def change_region(delta: np.ndarray, ref: np.ndarray, mask: np.ndarray, tile: int, labels, names, direct,
                  min_effect: float) -> str:
    """Where an image change ``delta`` (H, W, 3) lies, in the words of :func:`describe_tiles`.

    Tiles are chosen by the mean *absolute* relative change in luminance
    (a shift or a blur moves light within a tile, so its signed mean can
    vanish where the change is strong) and worded with the sign of the
    signed mean; a change whose tile means all stay below ``min_effect``
    is 'no visible change at this resolution'.
    """
    d = np.asarray(delta, np.float64)
    r_t = tile_means(np.asarray(ref, np.float64), mask, tile)
    signed = rel_lum(tile_means(d, mask, tile), r_t)
    lum = np.abs(d @ LUMINANCE)[..., None] * np.ones(3)
    mag = rel_lum(tile_means(lum, mask, tile), r_t)
    mx = float(np.max(np.abs(mag))) if mag.size else 0.0
    if mx < min_effect:
        return "no visible change at this resolution"
    chosen = np.abs(mag) >= max(0.3 * mx, min_effect)
    rel = np.where(signed < 0, -np.abs(mag), np.abs(mag))
    h, w = np.asarray(ref).shape[:2]
    return describe_tiles(rel, chosen, (h, w), tile, labels, names, direct)


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
        out.append(Candidate(name, texts.get(name, name), dm, dm, 1.0, 1.0 - dm / d0 if d0 > 0 else 0.0, ""))
    out.sort(key=lambda c: c.chi2)
    return out, d0


def variance_inflation(e, baseline, mask: np.ndarray) -> float:
    """How many times a bug multiplies the image's relative variance: (sum var / sum mean^2) against the baseline's."""
    def rel(x) -> float:
        m, v = x.mean.astype(np.float64)[mask], x.var.astype(np.float64)[mask]
        return float(np.sum(v) / max(np.sum(m * m), 1e-300))

    return rel(e) / max(rel(baseline), 1e-300)


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
        out.append(Candidate(name, texts.get(name, name), float(dist), float(dist), float(infl),
                             float(1.0 - dist / np.log(var_ratio)), ""))
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
