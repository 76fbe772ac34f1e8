"""A diffuse bounce drawn one way and weighted for another (mcrt.grade.explain.bounce), graded end to end.

The hand-ins are Mitsuba's: its path tracer with the first diffuse bounce
drawn here, in NumPy, as a student's program draws it (the grading-accuracy
classes' harness, :func:`mcrt.grade.accuracy.unprompted._first_bounce`),
never mcrt's renders of the family.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_diagnose import RES
from test_explain_programs import ctx  # noqa: F401 (the 32x32 assignment's context, a fixture)

from mcrt.grade.accuracy import unforeseen, unprompted
from mcrt.grade.accuracy.run import named_causes
from mcrt.grade.grader import grade_image


def _uniform_hemisphere_as_sphere(rng, n):
    """Uniform directions on the hemisphere (cos theta = u1) weighted with the whole sphere's pdf 1/(4 pi): f cos / pdf
    = 4 albedo cos, twice the 2 albedo cos of the hemisphere's."""
    u1, u2 = rng.random((2, len(n)))
    sin = np.sqrt(1.0 - u1 * u1)
    t, b = unforeseen._frame_of(n)
    phi = 2.0 * math.pi * u2
    d = (sin * np.cos(phi))[:, None] * t + (sin * np.sin(phi))[:, None] * b + u1[:, None] * n
    return d, 4.0 * u1


def _cosine_as_uniform(rng, n):
    """Cosine-distributed directions weighted with the uniform hemisphere's pdf 1/(2 pi): f cos / pdf = 2 albedo cos
    where the albedo belongs."""
    d, cos = unprompted._cosine_directions(rng, n)
    return d, 2.0 * cos


@pytest.mark.parametrize("draw, seed, value, words", [
    (_uniform_hemisphere_as_sphere, 91, {"bounce": "cosine", "factor": 2.0}, "the whole sphere's pdf 1/(4 pi)"),
    (_cosine_as_uniform, 92, {"bounce": "cosine_squared", "factor": 2.0}, "the uniform hemisphere's pdf 1/(2 pi)"),
])
def test_a_bounce_drawn_one_way_and_weighted_for_another_is_claimed(ctx, draw, seed, value, words):
    """Each hand-in's first bounce is claimed as drawn one way and weighted for another, in the program's words, and
    named as the light that bounces; the constant path weight at the first hit (which would scale the light the
    mirror sphere reflects too) is not what is claimed."""
    S = unprompted._first_bounce(np.zeros((RES, RES, 3)), spp=1024, seed=seed, draw=draw)
    res = grade_image("first_bounce", ctx, [S], spp=1024)
    ex = res.details["explanation"]
    assert ex["verdict"] == "claimed" and ex["family"] == "bounce", ex["sentence"]
    assert words in ex["sentence"] and "at the first surface a camera ray meets" in ex["sentence"], ex["sentence"]
    named = next(c for c in ex["candidates"] if c["mutant"] == ex["named"])
    assert {k: named["value"][k] for k in value} == value, named["value"]
    assert named_causes(res)[0] == ["indirect_scale"]
    assert res.score <= 0.75 * res.max_score


def test_a_right_first_bounce_is_no_bounce_mistake(ctx):
    """The harness with the right cosine-weighted bounce (weight the albedo): full marks, no cause claimed."""
    S = unprompted._first_bounce(np.zeros((RES, RES, 3)), spp=1024, seed=93,
                                 draw=lambda rng, n: (unprompted._cosine_directions(rng, n)[0], np.ones(len(n))))
    res = grade_image("first_bounce_right", ctx, [S], spp=1024)
    assert res.score == res.max_score, res.summary
