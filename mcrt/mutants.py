"""The bug catalogue: realistic estimator bugs that can be switched on in the tracer.

Each mutant imitates one mistake that students (and engineers) really make.
They exist to measure the power of the statistical tests and to explain a
failing render by the bug it most resembles. A mutant is chosen by name in
the API (``mutants=("nee_no_cos_light",)``) or on the command line
(``--mutant NAME``); a scene file cannot switch one on.
"""

from __future__ import annotations

from dataclasses import replace

from mcrt.scene import Scene

MUTANTS: dict[str, str] = {
    "rr_no_divide": "Russian roulette without dividing by the survival probability: at each diffuse bounce the path is "
    "absorbed with probability 0.75 and otherwise continues with its throughput times 0.8 (the 2023 course report's "
    "scheme) instead of divided by 0.25. Indirect light is too dark.",
    "nee_no_cos_light": "Next-event estimation without the cosine at the light: direct light too bright at grazing "
    "angles to the light, far from it.",
    "nee_no_cos_surface": "Next-event estimation without the cosine at the receiving surface: walls lit at grazing "
    "angles too bright.",
    "nee_no_inv_dist2": "Next-event estimation without the 1/d^2 of the geometry term: direct light wrong by the "
    "squared distance to the light (far surfaces much too bright).",
    "nee_no_area": "The light's pdf without its area (pdf 1 instead of 1/A): direct light scaled by 1/A (4x too dark "
    "for the 2x2 light).",
    "double_count": "Emission counted both by next-event estimation and when a BSDF-sampled ray after a diffuse bounce "
    "hits the light: direct light counted twice.",
    "uniform_as_cosine": "Uniform hemisphere directions weighted as if cosine-distributed: indirect light wrong "
    "(grazing directions over-weighted).",
    "ball_plus_normal": "Lambertian directions from a random point inside the unit ball plus the normal (the point "
    "must be on the sphere): not cosine-distributed, indirect light wrong.",
    "brdf_no_inv_pi": "Lambertian BRDF albedo instead of albedo/pi: every reflection pi times too bright.",
    "mirror_wrong_sign": "Mirror reflection with the wrong sign: the reflected ray points into the sphere, which "
    "turns black.",
    "no_jitter": "No pixel jitter: every sample through the pixel centre (aliased edges, box filter ignored).",
    "depth_off_by_one": "Maximum depth off by one: one bounce too many.",
    "no_offset": "No offset on continuation and shadow rays: rays leaving a surface can hit it again (shadow acne, "
    "dark speckles on curved and convex objects).",
    "shadow_unbounded": "Shadow rays not bounded by the distance to the light: whatever lies beyond the light (the "
    "ceiling) blocks it, so there is no direct light.",
    "gamma_output": "Output gamma-encoded (sRGB) instead of linear radiance.",
    "albedo_1pct": "One wall's albedo wrong by 1 % (wall BC, all channels times 0.99): the deliberately subtle bug.",
    "light_two_sided": "The light emitting from both sides: its upper side lights the ceiling around it.",
}


def check_mutants(names) -> frozenset[str]:
    """Validate mutant names; raise ValueError naming an unknown one."""
    names = frozenset(names or ())
    for n in names:
        if n not in MUTANTS:
            raise ValueError(f"unknown mutant {n!r}; known: {', '.join(MUTANTS)}")
    return names


def mutate_scene(scene: Scene, mutants: frozenset[str]) -> Scene:
    """Apply the mutants that change the scene rather than the estimator."""
    if "albedo_1pct" not in mutants:
        return scene
    walls = tuple(
        replace(w, albedo=tuple(0.99 * a for a in w.albedo)) if w.corners == ("B", "C") else w for w in scene.room.walls
    )
    if walls == scene.room.walls:
        raise ValueError("mutant albedo_1pct needs a wall BC")
    return replace(scene, room=replace(scene.room, walls=walls))
