"""The explanation stage's contract (mcrt.grade.candidates): families plug in, the best candidate's predicted
change leaves the remainder, and a claim rule decides what the feedback says. Synthetic images, seed 7."""

from __future__ import annotations

import numpy as np
import pytest

from mcrt.grade.candidates import CLAIMED, NONE, PARTIAL, Candidate, Inputs
from mcrt.grade.explain import explain
from mcrt.grade.explain.basis import Basis

H = W = 32


@pytest.fixture
def images():
    rng = np.random.default_rng(7)
    R = np.ones((H, W, 3)) * np.linspace(0.2, 1.0, W)[None, :, None]
    step = np.zeros((H, W, 3))
    step[:, W // 2:] = 0.1  # a change on the right half, far above the noise
    V = np.full((H, W, 3), 1e-4)
    S = R + step + rng.normal(0.0, 1e-2, R.shape)
    basis = Basis(camera="near", spp=1, base=R.astype(np.float32), var=np.zeros((H, W, 3), np.float32),
                  fine=R.astype(np.float32), fine_tan=1.0, fov_deg=90.0, max_depth=8)
    return S, R, V, step, Inputs(basis)


def family_of(change, name="right half brighter"):
    def fam(fit, inputs):
        return [Candidate("test", name, f"the {name}", fit.delta(change), 0, value=0.1, change=change)]

    fam.name = "test"
    return fam


def test_a_family_that_predicts_the_change_is_claimed_and_leaves_noise(images):
    S, R, V, step, inputs = images
    e = explain(S, R, V, np.ones((H, W), bool), inputs, families=(family_of(step), family_of(0.5 * step, "half")))
    assert e.verdict == CLAIMED and e.named is e.best and e.best.name == "right half brighter"
    assert e.explained > 0.95
    assert np.allclose(e.remainder, S - R - step)
    assert abs(float(np.std(e.remainder)) - 1e-2) < 2e-3  # what is left is the noise
    assert e.sentence.startswith("It looks like the right half brighter")


def test_no_candidate_claims_nothing_and_leaves_the_whole_difference(images):
    S, R, V, _, inputs = images
    e = explain(S, R, V, np.ones((H, W), bool), inputs, families=())
    assert e.verdict == NONE and e.named is None and e.best is None
    assert np.allclose(e.remainder, S - R)
    assert e.sentence.startswith("No single mistake we tried")


def test_a_claim_rule_plugs_in_and_a_partial_explanation_says_where_the_rest_is(images):
    S, R, V, step, inputs = images

    def partial(e, fit, inputs):
        e.verdict, e.remainder_where = PARTIAL, "on the right half"

    e = explain(S, R, V, np.ones((H, W), bool), inputs, families=(family_of(0.5 * step, "half"),), claim=partial)
    assert e.verdict == PARTIAL and e.named is None
    assert np.allclose(e.remainder, S - R - 0.5 * step)
    assert e.sentence.startswith("Partly like the half, which explains") and "on the right half" in e.sentence


# --------------------------------------------------------------------------
# Occam's rule (mcrt.grade.adequacy.occam): the simplest adequate explanation
# --------------------------------------------------------------------------


def _occam_case(eps: float):
    """A change (the right half 10 % brighter) explained by a 1-parameter family that predicts it ``eps`` too weak,
    and a 3-parameter family (a factor per channel, fitted) that absorbs the shortfall; graded by the production
    claim rule with the bias test's noise model. Noise: seed 1, standard deviation 0.01."""
    from mcrt.grade.adequacy import Scene2D, claim_rule
    from mcrt.stats.onesample import Noise

    rng = np.random.default_rng(1)
    labels = np.zeros((H, W), np.int16)
    labels[:, 16:] = 1
    labels[16:, :] = 2
    R = np.stack([0.2 + 0.1 * labels, 0.3 + 0.05 * labels, 0.25 * np.ones_like(labels)], axis=-1).astype(np.float64)
    var = np.full(R.shape, 1e-4)
    step = np.where((labels == 1)[..., None], 0.1 * R, 0.0)
    S = R + step + rng.standard_normal(R.shape) * np.sqrt(var)
    sc = Scene2D((8, 16, 0), 0.01, 0.003, 0.1, labels, ("left", "right", "floor", "nothing"))
    mask = np.ones((H, W), bool)
    basis = Basis(camera="near", spp=1, base=R.astype(np.float32), var=np.zeros(R.shape, np.float32),
                  fine=R.astype(np.float32), fine_tan=1.0, fov_deg=90.0, max_depth=8)

    def one(fit, inputs):
        a = (1 - eps) * step
        return [Candidate("one", "one factor", "the right half brighter", fit.delta(a), 1, change=a)]

    def three(fit, inputs):
        m = (labels == 1)[..., None] & fit.ok
        k = (np.sum(np.where(m, fit.w * fit.D * step, 0), axis=(0, 1))
             / np.sum(np.where(m, fit.w * step**2, 0), axis=(0, 1)))
        return [Candidate("three", "three factors", "the right half brighter per channel", fit.delta(k * step), 3,
                          change=k * step, generalises=("one",))]

    one.name, three.name = "one", "three"
    rule = claim_rule(S, R, mask, Noise(model=var, reference=np.zeros_like(var)), sc)
    return explain(S, R, var, mask, Inputs(basis), families=(one, three), claim=rule), (S, R, var)


def test_occam_claims_the_simpler_adequate_family_over_one_that_fits_insignificantly_better():
    """eps = 4 %: the 3-parameter family (a factor per channel, which nests the one factor) explains more of the
    difference (it ranks first, BIC included), but the 1-parameter one leaves noise too and the gain is not
    significant (closeness < OCCAM_Z): the simpler is claimed, and the more complex one is not named beside it."""
    from mcrt.grade.adequacy import OCCAM_Z, closeness
    from mcrt.grade.explain.fit import Fit

    e, (S, R, var) = _occam_case(0.04)
    assert e.verdict == CLAIMED and e.named.name == "one factor", [(c.name, c.explained) for c in e.candidates]
    three = next(c for c in e.candidates if c.name == "three factors")
    assert three.explained > e.named.explained  # the rule before Occam's would have claimed it
    assert e.adequacy.alternatives == []
    fit = Fit(S, R, var, np.ones(S.shape, bool), np.zeros(S.shape))  # as the engine builds it (no basis noise)
    assert closeness(fit, three, e.named) < OCCAM_Z


def test_occam_claims_the_complex_family_where_the_simple_one_leaves_structure():
    """eps = 10 %: the 1-parameter family leaves a structured remainder (the right half 1 % too dark): not
    adequate, so the 3-parameter family that fits is claimed."""
    e, _ = _occam_case(0.10)
    assert e.verdict == CLAIMED and e.named.name == "three factors"


def _halves(seed: int):
    """Two surfaces side by side, the right half 10 % too bright, noise sd 0.01 of the given seed, and the production
    claim rule for it: (S, R, var, step, rule, basis)."""
    from mcrt.grade.adequacy import Scene2D, claim_rule
    from mcrt.stats.onesample import Noise

    rng = np.random.default_rng(seed)
    labels = np.zeros((H, W), np.int16)
    labels[:, 16:] = 1
    R = np.stack([0.2 + 0.1 * labels, 0.3 + 0.05 * labels, 0.25 * np.ones_like(labels)], axis=-1).astype(np.float64)
    var = np.full(R.shape, 1e-4)
    step = np.where((labels == 1)[..., None], 0.1 * R, 0.0)
    S = R + step + rng.standard_normal(R.shape) * np.sqrt(var)
    sc = Scene2D((8, 16, 0), 0.01, 0.003, 0.1, labels, ("left", "right", "nothing"))
    basis = Basis(camera="near", spp=1, base=R.astype(np.float32), var=np.zeros(R.shape, np.float32),
                  fine=R.astype(np.float32), fine_tan=1.0, fov_deg=90.0, max_depth=8)
    rule = claim_rule(S, R, np.ones((H, W), bool), Noise(model=var, reference=np.zeros_like(var)), sc)
    return S, R, var, step, rule, basis


def test_a_description_that_leaves_structure_is_no_partial_cause():
    """A description (Candidate.describes, as any monotone curve is) that predicts 80 % of the change (the right half
    10 % brighter, noise of seed 1) and a cause that predicts 40 % of it, under the production claim rule: neither
    leaves noise. "Partly like" the description would point at a step that is not wrong, so nothing is claimed or
    led with, the difference is placed on the right half, and the closest named is the cause, not the description."""
    S, R, var, step, rule, basis = _halves(1)

    def curve(fit, inputs):
        a = 0.8 * step
        return [Candidate("tone_curve", "curve", "the values through a curve", fit.delta(a), 1, change=a, describes=True)]

    def cause(fit, inputs):
        a = 0.4 * step
        return [Candidate("cause", "cause", "the right half lit too much", fit.delta(a), 1, change=a)]

    curve.name, cause.name = "curve", "cause"
    mask = np.ones((H, W), bool)
    e = explain(S, R, var, mask, Inputs(basis), families=(curve, cause), claim=rule)
    assert e.best.name == "curve" and e.verdict == NONE and e.named is None, (e.verdict, e.sentence)
    assert e.sentence.startswith("No single mistake we tried") and "Partly" not in e.sentence, e.sentence
    assert "the closest, the right half lit too much, explains" in e.sentence and "on right" in e.sentence, e.sentence


@pytest.mark.parametrize("a, verdict", [(0.2, NONE), (0.4, PARTIAL)])
def test_a_cause_leads_a_partial_reading_only_where_it_explains_half(a, verdict):
    """A cause that predicts a of the change (the right half 10 % brighter, noise of seed 2), under the production
    claim rule: it leaves structure either way. At a = 0.2 it explains 1 - 0.8^2 = 36 % of the difference: nothing
    is claimed or led with ("partly like" it would send the student to a step that may not be wrong), the difference
    is placed on the right half and the cause named as the closest with its share; at a = 0.4 (64 %) it leads a
    partial reading."""
    S, R, var, step, rule, basis = _halves(2)

    def cause(fit, inputs):
        return [Candidate("cause", "cause", "the right half lit too much", fit.delta(a * step), 1, change=a * step)]

    cause.name = "cause"
    mask = np.ones((H, W), bool)
    e = explain(S, R, var, mask, Inputs(basis), families=(cause,), claim=rule)
    assert e.verdict == verdict and e.named is None, (e.verdict, e.sentence)
    if verdict == NONE:
        assert e.sentence.startswith("No single mistake we tried") and "Partly" not in e.sentence, e.sentence
        assert "the closest, the right half lit too much, explains 3" in e.sentence and "on right" in e.sentence
    else:
        assert e.sentence.startswith("Partly like the right half lit too much"), e.sentence


def test_a_camera_family_must_be_seen_beyond_the_emitters():
    """A room of value 0.5 with a bright 8 x 8 emitter (20) and a darker box (0.2), noise sd 0.01 (seed 5). A camera
    candidate whose change lies on the emitter's outline alone (a warp fitting the light's shape) is not seen beyond
    the emitters; one that also moves the box's edges is, as is any family that is not a camera's."""
    from mcrt.grade.adequacy import Scene2D, seen_beyond_emitters
    from mcrt.grade.explain.fit import Fit

    rng = np.random.default_rng(5)
    R = np.full((H, W, 3), 0.5)
    R[4:12, 12:20] = 20.0
    R[20:28, 6:14] = 0.2
    outline = np.zeros_like(R)
    outline[3, 12:20] = outline[12, 12:20] = 2.0  # the emitter one pixel taller
    edges = outline.copy()
    edges[20:28, 14] = -0.3  # and the box one pixel wider
    sc = Scene2D((8, 16, 0), 0.01, 0.003, 0.1, np.zeros((H, W), np.int16), ("room", "nothing"))
    for change, seen in ((outline, False), (edges, True)):
        S = R + change + rng.normal(0.0, 1e-2, R.shape)
        fit = Fit(S, R, np.full(R.shape, 1e-4), np.ones(R.shape, bool), np.zeros(R.shape))
        assert seen_beyond_emitters(Candidate("fov", "fov", "a field of view", fit.delta(change), 1, change=change),
                                    fit, sc) is seen
        assert seen_beyond_emitters(Candidate("light_size", "size", "the light's size", fit.delta(change), 1,
                                              change=change), fit, sc)


def _step_fit(seed: int):
    """(fit, step): a flat image 0.5 whose right half is 0.05 brighter, with noise of sd 0.01 (``seed``)."""
    from mcrt.grade.explain.fit import Fit

    rng = np.random.default_rng(seed)
    R = np.full((H, W, 3), 0.5)
    step = np.zeros_like(R)
    step[:, W // 2:] = 0.05
    S = R + step + rng.normal(0.0, 1e-2, R.shape)
    return Fit(S, R, np.full(R.shape, 1e-4), np.ones(R.shape, bool), np.zeros(R.shape)), step


def test_closeness_is_significant_for_a_clearly_better_fit_and_signed():
    """Vuong's statistic: the exact change against one 30 % too weak, on noise of seed 3 (sd 0.01): far beyond
    OCCAM_Z for the exact one, as far below it the other way round, and 0 for a candidate against itself."""
    from mcrt.grade.adequacy import OCCAM_Z, closeness

    fit, step = _step_fit(3)
    exact = Candidate("a", "exact", "", fit.delta(step), 1, change=step)
    weak = Candidate("b", "weak", "", fit.delta(0.7 * step), 1, change=0.7 * step)
    assert closeness(fit, exact, weak) > 3 * OCCAM_Z
    assert closeness(fit, weak, exact) < -3 * OCCAM_Z
    assert closeness(fit, exact, exact) == 0.0


def test_another_change_of_the_same_objects_geometry_that_fits_better_is_a_rival():
    """mcrt.grade.adequacy.geometry_rival on noise of seed 4 (sd 0.01): a claimed size of the tetrahedron that fits
    a step 80 % as well as its place does has that place for a rival (the words then say its geometry); the place
    of the sphere is no rival of it, nor is a place that fits worse, nor one the size beats by CONFIRM_Z."""
    from mcrt.grade.adequacy import geometry_rival

    fit, step = _step_fit(4)

    def cand(family, value, k):
        return Candidate(family, family, "", fit.delta(k * step), 1, value=value, change=k * step)

    size = cand("object_size", {"object": "tetrahedron", "scale": 0.7}, 0.8)
    place = cand("object_moved", ["tetrahedron", "y", 0.5], 1.0)
    sphere = cand("object_moved", ["sphere", "x", 0.5], 1.0)
    assert geometry_rival(size, [size, place], fit) is place
    assert geometry_rival(size, [size, sphere], fit) is None
    assert geometry_rival(place, [place, size], fit) is None  # the size fits worse
    exact = cand("object_size", {"object": "tetrahedron", "scale": 0.7}, 1.0)
    weak = cand("object_moved", ["tetrahedron", "y", 0.5], 0.3)
    assert geometry_rival(exact, [exact, weak], fit) is None
    assert geometry_rival(cand("albedo", [0.5, 0.5, 0.5], 0.8), [place], fit) is None  # not a geometry claim


def test_the_camera_warp_shifts_a_point_of_light_without_changing_its_footprint():
    """A fine image (FINE times finer, WIDE times wider, exactly) holding one bright fine pixel, warped by the
    pixel-offset family's shifts from 0 to 1/2 pixel in steps of 1/20: the point keeps its total light at every shift
    and its centroid moves with the shift (each grade pixel's footprint is the same box whatever the shift). With
    fewer warp samples than fine pixels the footprint narrows between samples, the total ripples with the shift, and
    so does the chi^2 of a shift: a quarter-pixel shift is then not found, and a rotation is claimed in its place."""
    import math

    from mcrt.grade.explain.basis import FINE, WIDE
    from mcrt.grade.explain.camera import _Warp

    h = w = 20
    n = round(FINE * WIDE * w)
    assert n == FINE * WIDE * w  # the fine grid lies exactly on the grade grid
    yy, xx = np.mgrid[0:n, 0:n]
    fine = np.zeros((n, n, 3), np.float32)
    fine[n // 2 + 1, n // 2 + 2, 0] = 1.0  # red: a point
    fine[..., 1] = np.exp(-((xx - n / 2) ** 2 + (yy - n / 2) ** 2) / (2 * 6.0**2))  # green: a smooth blob
    b = Basis(camera="near", spp=1, base=np.zeros((h, w, 3), np.float32), var=np.zeros((h, w, 3), np.float32),
              fine=fine, fine_tan=WIDE * math.tan(math.radians(45.0)), fov_deg=90.0, max_depth=8)
    wp = _Warp(b)
    jj, ii = np.mgrid[0:h, 0:w]
    totals, cx = [], []
    for d in np.arange(0.0, 0.55, 0.05):
        img = wp.image(dx=d, dy=d)
        totals.append(img[..., 0].sum())
        cx.append((img[..., 1] * ii).sum() / img[..., 1].sum())
    np.testing.assert_allclose(totals, totals[0], rtol=1e-5)
    np.testing.assert_allclose(np.diff(cx), -0.05, atol=2e-3)  # what lies at x is seen at x - dx


def test_the_adequacy_rule_tries_what_chi2_cannot_tell_from_the_best():
    """Ranked candidates (a rotation best, an albedo, a pixel shift, then a blur with a third of a small difference but
    a chi^2 within noise's spread of the best's): the blur's remainder is tested too, beside the camera's two families
    (one reading, a misregistration, which does not crowd the blur out); with no spread it is left out by its share."""
    from mcrt.grade.adequacy import tried_candidates

    z = np.zeros((2, 2, 3))
    cands = [Candidate(f, f, f, chi2, 1, explained=e, change=z) for f, chi2, e in
             (("rotation", 100.0, 1.0), ("albedo", 110.0, 0.9), ("pixel_offset", 112.0, 0.85), ("blur", 150.0, 0.3),
              ("depth", 400.0, 0.1))]
    tried = [c.family for c in tried_candidates(cands, within=60.0)]
    assert tried == ["rotation", "albedo", "pixel_offset", "blur"], tried
    assert [c.family for c in tried_candidates(cands)] == ["rotation", "albedo", "pixel_offset"]


def test_a_candidate_no_better_than_no_change_is_never_tried():
    """A difference close to noise: a fitted change that gains less chi^2 over the reference than its parameters times
    ln n (BIC's price) is neither tried nor listed as a possibility, whatever its chi^2 beside the best's; one that
    gains more is tried."""
    import math

    from mcrt.grade.adequacy import beats_no_change, tried_candidates
    from mcrt.grade.explain.fit import Fit

    rng = np.random.default_rng(7)
    R = np.ones((16, 16, 3))
    fit = Fit(R + 0.1 * rng.standard_normal(R.shape), R, np.full(R.shape, 0.01), np.ones(R.shape, bool), 0.0)
    price = math.log(fit.n)
    z = np.zeros(R.shape)
    strong = Candidate("reflectance", "r", "r", fit.chi0 - 4 * price, 3, explained=1.0, change=z)
    weak = Candidate("fov", "f", "f", fit.chi0 - 0.5 * price, 1, explained=0.2, change=z)
    worse = Candidate("blur", "b", "b", fit.chi0 + 1.0, 1, explained=-0.1, change=z)
    assert beats_no_change(strong, fit) and not beats_no_change(weak, fit) and not beats_no_change(worse, fit)
    within = 6 * price  # all three within noise's spread of the best
    assert [c.family for c in tried_candidates([strong, weak, worse], within)] == ["reflectance", "fov", "blur"]
    assert [c.family for c in tried_candidates([strong, weak, worse], within, fit=fit)] == ["reflectance"]
