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
