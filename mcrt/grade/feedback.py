"""Feedback text: the summary line, the explanation's sentences and the words for numbers.

Everything a student reads that is not a criterion's own one-line verdict
is worded here, so that image mode and code mode say the same thing the
same way ("Full marks: 100/100.").
"""

from __future__ import annotations

import math

import numpy as np

from mcrt.grade.candidates import AMBIGUOUS, CLAIMED, DESCRIBED, INDISTINCT, PARTIAL, TIE, Explanation
from mcrt.util.fmt import short as num


def fmt_pct(x: float) -> str:
    """A share as a percentage: two significant digits below 10 %, whole per cents above."""
    return f"{100 * x:.2g} %" if abs(x) < 0.1 else f"{100 * x:.0f} %"


def spp_text(spp: float) -> str:
    return f"{spp:.0f}" if spp >= 10 else f"{spp:.1f}"


def fmt_values(v, digits: int = 2) -> str:
    """One value, or an RGB triple when its channels differ: '0.60', '(0.74, 0.20, 0.15)'; with more decimals where
    the smallest would show as 0 ('0.0042', not '0.00')."""
    v = tuple(float(x) for x in v)
    small = min((abs(x) for x in v if x != 0), default=1.0)
    if small < 0.5 * 10.0 ** -digits:
        digits = 1 - math.floor(math.log10(small))
    if len(set(round(x, digits) for x in v)) == 1:
        return f"{v[0]:.{digits}f}"
    return "(" + ", ".join(f"{x:.{digits}f}" for x in v) + ")"


def summary(tests, score: float, max_score: float, *, blocked: str | None, headline: str, mode: str) -> str:
    """The one-line summary of a graded hand-in: full marks, or the points lost and why.

    Image mode names the lost criteria and the first failure's verdict
    (then the headline of the bias test); code mode quotes the first two
    failed checks.
    """
    shown = num(score)
    if mode == "code":
        failed = [t for t in tests if t.score < t.max_score]
        if failed:
            return f"{shown}/{max_score:g}. " + "; ".join(f"{t.name}: {t.output.splitlines()[0][:160]}" for t in failed[:2])
    else:
        failed = [t for t in tests if t.status in ("failed", "not graded") and t.max_score > 0]
    if not failed:
        return (f"Full marks: {shown}/{max_score:g}. " + (headline or "")).strip()
    first = failed[0]
    if blocked:
        text = f"{shown}/{max_score:g}; nothing after '{first.title}' could be graded."
    else:
        lost = ", ".join(f"{t.title.split(' (')[0].lower()} (-{num(t.max_score - t.score)})" for t in failed)
        text = f"{shown}/{max_score:g}; points lost: {lost}."
    if first.name != "unbiased":
        text += f" {first.title}: {first.output.split('; ')[0]}."
    if headline and headline != "No significant bias.":
        text += f" {headline}"
    return text.strip()


#: The kinds of mistake the explanation families (mcrt.grade.explain.families.FAMILIES) try, in a student's words.
_TRIED = ("No single mistake we tried (the catalogued bugs, the scene's colours, light, objects and camera, "
          "the path depth, encodings, tone curves, clamped samples, colour channels, light counted twice, a light "
          "sample's weight, fall-offs, bloom, "
          "resampling, materials, object sizes, a BRDF's normalisation, the film's other buffers, memory layouts, "
          "missing pixels and blur)")


#: A monotone curve whose outputs over the reference's values (its 10th, 50th and 99th percentiles, the light among
#: them) stay within this ratio maps the scene to one value: the image holds no view, not values bent by a curve.
FLAT = 1.25


def flat_level(value) -> float | None:
    """The one value a monotone curve's ``value`` (its 'maps': [reference, image] pairs) maps the scene to, where its
    outputs are within :data:`FLAT` of one another and above 0; else None."""
    maps = value.get("maps") if isinstance(value, dict) else None
    out = [q for _, q in maps] if maps else []
    if len(out) < 2 or min(out) <= 0 or max(out) > FLAT * min(out):
        return None
    return float(np.median(out))


def explanation_words(e: Explanation) -> tuple[str, str]:
    """The sentence (for the bias test's output) and the headline (for the summary) of an explanation."""
    best, where = e.best, e.where
    if e.verdict == CLAIMED and e.adequacy is not None:  # the adequacy rule: the remainder is noise
        alts = e.adequacy.alternatives
        sentence = (f"It looks like {best.text}: what is left after it is consistent with noise "
                    f"({100 * best.explained:.0f} % of the difference explained)"
                    + ("; so would " + " or ".join(f"{t} ({100 * x:.0f} %)" for _, t, x in alts)
                       + ": the image cannot tell them apart" if alts else "")
                    + (f"; it changes the image {best.where}" if best.where else "") + ".")
        return sentence, f"It looks like {best.text}" + (f", or {alts[0][1]}." if alts else ".")
    if e.verdict == CLAIMED:
        alt = next((c for c in e.candidates[1:3] if c.family != best.family and not c.catalogue
                    and c.explained >= best.explained - TIE), None)
        sentence = (f"It looks like {best.text}: that explains {100 * best.explained:.0f} % of the difference"
                    + (f" (so would {alt.text}, {100 * alt.explained:.0f} %)" if alt else "")
                    + (f"; it changes the image {best.where}" if best.where else "") + ".")
        return sentence, f"It looks like {best.text}."
    if e.verdict == AMBIGUOUS and e.broader and e.adequacy.alternatives:  # an object's geometry, which part unsaid
        other = e.adequacy.alternatives[0][1]
        sentence = (f"It could be {best.text}, which leaves only noise, or {other}, which fits as well or better "
                    f"though it leaves more than noise somewhere: {e.broader[1]}.")
        return sentence, f"It could be {best.text}, or {other}: {e.broader[1]}."
    if e.verdict == AMBIGUOUS:  # causes of other readings leave noise as well: the image cannot say which
        texts = [best.text] + [t for _, t, _ in e.adequacy.alternatives]
        each = ", ".join(texts[:-1]) + ", or " + texts[-1]
        where_b = f"; the difference changes the image {best.where}" if best.where else ""
        if len(texts) == 1:  # a surface out of view alone leaves noise (Candidate.out_of_view): nothing confirms it
            sentence = (f"It could be {best.text}: what is left after it is consistent with noise, but no pixel sees "
                        "that surface, only the light it reflects, which other mistakes change alike (a biased "
                        f"estimate of each pixel, paths cut short), so no cause is claimed{where_b}.")
            return sentence, f"It could be {best.text}, but the image cannot confirm it."
        why = ("a surface no pixel sees shows only in the light it reflects, which the others change alike" if
               best.out_of_view else "none fits significantly better")
        sentence = (f"It could be {each}: each leaves only noise and {why}, so the image cannot tell which, and no "
                    f"cause is claimed{where_b}; check each of them.")
        return sentence, f"It could be {each}: the image cannot tell which."
    if e.verdict == DESCRIBED:  # only a description leaves noise (Candidate.describes): how it differs, no cause
        return _described_words(e)
    if e.verdict == PARTIAL:
        rest = f"something else is wrong {e.remainder_where}" if e.remainder_where else "something else is wrong too"
        # The share is of the difference's chi^2 beyond noise: a remainder on one object can be a sliver of it.
        share = (f"{100 * best.explained:.0f} %" if best.explained < 0.995 else "nearly all") + " of the difference"
        more = f"; {e.broader[1]}" if e.broader else ""
        sentence = f"Partly like {best.text}, which explains {share}; {rest}{more}."
        return sentence, f"Partly like {best.text}; {rest}{more}."
    if e.verdict == INDISTINCT:  # it fits, but no better than noise would let anything fit
        gain = e.chi2_none - best.chi2
        sentence = (f"{_TRIED} stands out: the difference is too close to the noise to tell them apart (the closest, "
                    f"{best.text}, lowers chi-square by {gain:.0f} where noise alone varies it by about "
                    f"{math.sqrt(2 * e.terms):.0f})")
    else:
        # A description (any monotone curve) is no mistake, a flexible fit's share no evidence: the closest named is
        # the closest cause.
        near = next((c for c in e.candidates if not (c.describes or c.flexible)), None)
        sentence = (f"{_TRIED} explains most of the difference"
                    + (f": the closest, {near.text}, explains {100 * max(near.explained, 0):.0f} %" if near else ""))
    if e.remainder_where and e.broader:  # no mistake tried fits, but the part of the light that differs is known
        return (sentence + f"; but {e.broader[1]}. The difference sits {e.remainder_where}.",
                f"No single mistake we tried explains the difference, but {BROADER_HEADLINES[e.broader[0]]}.")
    if e.remainder_where:  # the adequacy rule placed the difference on objects
        return (sentence + f". The difference sits {e.remainder_where}.",
                f"No single mistake we tried explains the difference; it sits {e.remainder_where}.")
    sentence += (f". The image differs {where}" if where else "") + "."
    headline = "No single mistake we tried explains the difference" + (f"; it differs {where}" if where else "") + "."
    return sentence, headline


#: A broader reading's words for a headline where it stands beside no lead (nothing we tried explains most): those
#: of mcrt.grade.broader.bounced_light, direct_light and sphere_alone.
BROADER_HEADLINES = {"bounced_light": "the direct light is right and the light that bounced off other surfaces differs",
                     "direct_light": "the light seen directly and the bounced light are right, and the light the "
                                     "first surface a camera ray meets receives straight from the lamp differs",
                     "sphere_alone": "the difference lies on the mirror sphere's own pixels alone: the sphere itself "
                                     "or what it shows differs"}


def _described_words(e: Explanation) -> tuple[str, str]:
    """The sentence and headline of a DESCRIBED explanation: a curve on the values, said, its broader reading
    (mcrt.grade.broader.after_rendering) where it has one."""
    best = e.best
    where_b = f", changing the image {best.where}" if best.where else ""
    level = flat_level(best.value)
    if level is not None:  # the curve maps the darkest wall and the light alike: no view of the scene is left
        sentence = (f"The image is nearly one value everywhere (about {num(level)}), where the scene's light and its "
                    f"darkest walls alike should show{where_b}: no view of the scene is left, so no cause is "
                    "claimed; look at what each pixel's ray meets first (the camera's field of view and directions, "
                    "a surface covering the view) and at how the values are written (every pixel given one value)")
        return sentence + ".", "The image is nearly one value everywhere: no view of the scene is left."
    if e.broader:  # the light seen directly changed with the room, otherwise than by a scale (mcrt.grade.broader)
        sentence = (f"The difference depends on each pixel's value alone, as {best.text} would make it (what is "
                    f"left is consistent with noise){where_b}; no common tone map, clamp or encoding matches that "
                    f"curve, but {e.broader[1]}.")
        return sentence, ("The values went through a curve after rendering, on their way to the file; no common "
                          "curve matches.")
    sentence = (f"The difference depends on each pixel's value alone, as {best.text} would make it (what is left "
                f"is consistent with noise){where_b}; no common tone map, clamp or encoding matches that curve, "
                "so no cause is claimed: if your program changes the values before saving, check that step; if "
                "not, look at what scales light by brightness (a BRDF's or the light's factors).")
    return sentence, "The difference follows each pixel's value, as a curve on the values would; no common curve matches."


def bias_family_text(bt, th) -> str:
    """The bias test's family of tests, in words: the tile sizes, the channels, the level and the effect."""
    sizes = [f"{t}x{t}" for t in [s.tile for s in bt.scales] if t > 0]
    sizes = (", ".join(sizes[:-1]) + " and " + sizes[-1] if len(sizes) > 1 else "".join(sizes)) + " pixel tiles"
    if any(s.tile == 0 for s in bt.scales):
        sizes += " and the whole image"
    return (f"{sizes}, RGB; Holm at a family-wise error rate of {th.alpha:g}; "
            f"relative effects of {fmt_pct(th.min_effect)} or more")


#: Border displacement (pixels) beyond which the first-order registration fit describes nothing: its numbers are then
#: not given, only that the view differs (a scrambled or far-off image fits shifts of tens of pixels).
FIRST_ORDER_LIMIT = 8.0


def registration_text(reg, shape, min_shift: float) -> str:
    """The misregistration finding: how the camera differs, and what to check."""
    if reg.edge_displacement > FIRST_ORDER_LIMIT:
        return ("the image does not line up with the reference: fitted as a small camera change it would move its "
                f"border by {reg.edge_displacement:.0f} pixels, far beyond what such a fit measures, so it says only "
                f"that the view differs (p = {reg.p:.2g}); check the camera (field of view, eye, look-at and up "
                "vectors, the pixel-to-ray mapping) and where each pixel is written (row and column indices, the row "
                "stride, tiles' offsets)")
    h, w = shape
    radius = 0.5 * float(np.hypot(h - 1, w - 1))
    parts = []
    if np.hypot(*reg.shift) >= min_shift:
        parts.append(f"shifted by ({reg.shift[0]:+.2f}, {reg.shift[1]:+.2f}) pixels (right, down)")
    if abs(reg.zoom) * radius >= min_shift:
        parts.append(f"a field of view about {fmt_pct(abs(reg.zoom))} {'wider' if reg.zoom > 0 else 'narrower'} "
                     "(in tan(fov/2))")
    if abs(reg.roll) * radius >= min_shift:
        parts.append(f"rotated by about {np.degrees(abs(reg.roll)):.2g} degrees")
    return ("the camera does not match the reference: the image is " + ", ".join(parts or ["misregistered"])
            + f" (up to {reg.edge_displacement:.2f} pixels at the border; a first-order fit, "
            f"p = {reg.p:.2g}); check the pixel centre ((i + 0.5) / width), the field of view "
            "(horizontal, in degrees) and the camera's eye, look-at and up vectors")


def filter_text(st, blur: bool, spp_eff: float, spp: int | None) -> str:
    """The filter finding: correlated noise and softened edges (noise correlated along one direction alone: pixels
    that share random numbers)."""
    axis = getattr(st, "correlation_axis", "")
    if axis and st.correlation > 0 and not blur:
        return (f"neighbouring pixels' noise is correlated along the {axis} alone ({st.correlation:.2f}), not across "
                f"them: pixels that share random numbers along the {axis} (one seed or random stream for every "
                f"{axis[:-1]} or worker), or a filter along one axis; a Monte-Carlo render's pixels are independent: "
                "give each pixel its own random numbers")
    how = [f"neighbouring pixels' noise is correlated ({st.correlation:.2f})"] if st.correlation > 0 else []
    if blur:
        how.append(f"edges are {'softened' if st.blur > 0 else 'sharpened'} as by a filter of about "
                   f"{np.sqrt(abs(st.blur)):.2g} pixels")
    low = (f"; its noise is like {spp_text(spp_eff)} spp where {spp} were declared" if spp and np.isfinite(spp_eff)
           and spp_eff > 4 * spp else "")
    return ("the image was filtered (blurred, denoised or resampled): " + " and ".join(how) + low
            + "; a Monte-Carlo render's pixels are independent: hand in the unfiltered render")


def repeats_text(r) -> str:
    """The finding of noise that repeats between pixels apart (mcrt.grade.copytest): where, how strongly, the usual
    causes."""
    where, how = (("rows apart in one column", "one seed or generator state for every row, or a generator copied "
                   "into each thread or worker that renders rows") if r.axis == "rows" else
                  ("columns apart in one row", "one seed for every column, or seeds from a clock that had not ticked "
                   "between the pixels of a row"))
    return (f"the noise repeats: pixels {r.k} {where} have alike noise (correlation {r.correlation:.2f} over "
            f"{r.pairs} pairs, p = {r.p:.2g}), so they drew the same random numbers ({how}); a Monte-Carlo "
            "render's pixels are independent: give each pixel, thread or pass its own seed, or draw every number "
            "from one stream")


def denoised_text(st, times: float, spp: int) -> str:
    """The finding of noise taken out of the surfaces (mcrt.grade.stages.noise.removed) where neighbouring pixels are
    alike, though no single blur explains the image: a filter that keeps edges."""
    how = "its edges are softened" if st.blur > 0 else "neighbouring pixels are alike"
    return (f"the image was denoised or smoothed by a filter that keeps edges (bilateral, total variation, a guided "
            f"filter, a denoiser): the noise within its surfaces is about {times:.0f}x less than {spp} spp leaves, and "
            f"{how}, while no single blur explains it; such a filter also shifts the shading near edges and shadows. "
            "A Monte-Carlo render's pixels are independent: hand in the unfiltered render")


def places_text(pixels: float, ordered: float) -> str:
    """The finding of a correct render's values in other places (mcrt.grade.stages.bias.values_elsewhere)."""
    return (f"the image holds a correct render's values in the wrong places: sorted, its values match the reference's "
            f"(within {fmt_pct(ordered)} of the mean on average), but pixel by pixel they differ by {fmt_pct(pixels)}; "
            "pixels were written to other pixels' places: check where each pixel is written (a permutation or an "
            "index array not undone, an array compacted while its pixel indices were not, workers' rows or tiles "
            "placed wrongly)")


def patches_text(patch: np.ndarray, effects: list[float], names: list[str]) -> str:
    """The patch finding: where the pixels off together lie, how many, and by how much (no cause is claimed: a
    shadow missing, light leaking and a highlight misplaced all look so)."""
    rows, cols = np.nonzero(patch)
    how = " and ".join(f"{'brighter' if e > 0 else 'darker'} by {fmt_pct(abs(e))} on average" for e in effects)
    where = ", ".join(names[:-1]) + (" and " if len(names) > 1 else "") + names[-1] if names else "the image"
    return (f"A patch of {int(patch.sum())} touching pixels is {how}, more than noise allows (rows {int(rows.min())} "
            f"to {int(rows.max())}, columns {int(cols.min())} to {int(cols.max())}, on {where}): something on that "
            "part of the image differs from the scene, such as a shadow missing or misplaced, light that leaks or "
            "a reflection in the wrong place")


def pixels_text(pix: np.ndarray) -> str:
    """The wrong-pixels finding: how many, the first, and the usual causes."""
    first = np.argwhere(pix)[0]
    return (f"{int(pix.sum())} pixels are darker than any correct render's noise allows (the first at row "
            f"{int(first[0])}, column {int(first[1])}): rays that miss geometry (cracks between triangles, "
            "a hit test's epsilon) or shadow rays that hit the surface they start from")
