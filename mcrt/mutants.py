"""The bug catalogue: realistic rendering bugs that can be switched on in either host of the estimator.

Each mutant imitates one mistake that students (and engineers) really make.
They exist to measure the power of the statistical tests and to explain a
failing render by the bug it most resembles. A mutant is chosen by name in
the API (``mutants=("nee_no_cos_light",)``) or on the command line
(``--mutant NAME``); a scene file cannot switch one on.

A mutant is not a branch in the physics: it is a value of a typed option,
of the estimator (a field of :class:`mcrt.options.Mutations`), the camera
(:class:`mcrt.camera.Pinhole`'s jitter), the output encoding
(:func:`mcrt.srgb.encode_output`) or the scene.
The standalone tracer and the Mitsuba plugin take the same options, so every
mutant runs on both.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

from mcrt.options import Mutations
from mcrt.scene import Scene


def _albedo_1pct(scene: Scene) -> Scene:
    walls = tuple(
        replace(w, albedo=tuple(0.99 * a for a in w.albedo)) if w.corners == ("B", "C") else w for w in scene.room.walls
    )
    if walls == scene.room.walls:
        raise ValueError("mutant albedo_1pct needs a wall BC")
    return replace(scene, room=replace(scene.room, walls=walls))


@dataclass(frozen=True)
class Mutant:
    """One catalogued bug: what it does, and the option values that make it."""

    description: str
    mutations: dict = field(default_factory=dict)  # fields of mcrt.options.Mutations and their buggy values
    jitter: bool = True  # False: every camera sample through the pixel centre
    output: str = "linear"  # 'srgb': the image written sRGB-encoded
    scene: Callable[[Scene], Scene] | None = None  # a change of the scene itself

    def __post_init__(self):
        Mutations(**self.mutations)  # typed: an unknown field or a bad value fails here, on import


CATALOGUE: dict[str, Mutant] = {
    "rr_no_divide": Mutant(
        "Russian roulette without dividing by the survival probability: at each diffuse bounce the path is "
        "absorbed with probability 0.75 and otherwise continues with its throughput times 0.8 (the 2023 "
        "course report's scheme) instead of divided by 0.25. Indirect light is too dark.",
        mutations={"roulette": "course2023"},
    ),
    "nee_no_cos_light": Mutant(
        "Next-event estimation without the cosine at the light: direct light too bright at grazing angles to "
        "the light, far from it.",
        mutations={"nee_cos_light": False},
    ),
    "nee_no_cos_surface": Mutant(
        "Next-event estimation without the cosine at the receiving surface: walls lit at grazing angles too "
        "bright.",
        mutations={"nee_cos_surface": False},
    ),
    "nee_no_inv_dist2": Mutant(
        "Next-event estimation without the 1/d^2 of the geometry term: direct light wrong by the squared "
        "distance to the light (far surfaces much too bright).",
        mutations={"nee_inv_dist2": False},
    ),
    "nee_no_area": Mutant(
        "The light's pdf without its area (pdf 1 instead of 1/A): direct light scaled by 1/A (4x too dark for "
        "the 2x2 light).",
        mutations={"nee_pdf_area": False},
    ),
    "double_count": Mutant(
        "Emission counted both by next-event estimation and when a BSDF-sampled ray after a diffuse bounce "
        "hits the light: direct light counted twice.",
        mutations={"count_emission": "always"},
    ),
    "uniform_as_cosine": Mutant(
        "Uniform hemisphere directions weighted as if cosine-distributed: indirect light wrong (grazing "
        "directions over-weighted).",
        mutations={"lambertian_sampler": "uniform_as_cosine"},
    ),
    "ball_plus_normal": Mutant(
        "Lambertian directions from a random point inside the unit ball plus the normal (the point must be on "
        "the sphere): not cosine-distributed, indirect light wrong.",
        mutations={"lambertian_sampler": "ball_plus_normal"},
    ),
    "brdf_no_inv_pi": Mutant(
        "Lambertian BRDF albedo instead of albedo/pi: every reflection pi times too bright.",
        mutations={"brdf_inv_pi": False},
    ),
    "mirror_wrong_sign": Mutant(
        "Mirror reflection with the wrong sign: the reflected ray points into the sphere, which turns black.",
        mutations={"mirror_sign": -1.0},
    ),
    "no_jitter": Mutant(
        "No pixel jitter: every sample through the pixel centre (aliased edges, box filter ignored).",
        jitter=False,
    ),
    "depth_off_by_one": Mutant(
        "Maximum depth off by one: one bounce too many.",
        mutations={"extra_depth": 1},
    ),
    "no_offset": Mutant(
        "No offset on continuation and shadow rays: rays leaving a surface can hit it again (shadow acne, "
        "dark speckles on curved and convex objects).",
        mutations={"spawn_offset": False},
    ),
    "shadow_unbounded": Mutant(
        "Shadow rays not bounded by the distance to the light: whatever lies beyond the light (the ceiling) "
        "blocks it, so there is no direct light.",
        mutations={"shadow_bounded": False},
    ),
    "gamma_output": Mutant(
        "Output gamma-encoded (sRGB) instead of linear radiance.",
        output="srgb",
    ),
    "albedo_1pct": Mutant(
        "One wall's albedo wrong by 1 % (wall BC, all channels times 0.99): the deliberately subtle bug.",
        scene=_albedo_1pct,
    ),
    "light_two_sided": Mutant(
        "The light emitting from both sides: its upper side lights the ceiling around it.",
        mutations={"light_one_sided": False},
    ),
}


#: Name -> description of every catalogued bug.
MUTANTS: dict[str, str] = {name: m.description for name, m in CATALOGUE.items()}


def check_mutants(names) -> frozenset[str]:
    """Validate mutant names; raise ValueError naming an unknown one."""
    names = frozenset(names or ())
    for n in names:
        if n not in CATALOGUE:
            raise ValueError(f"unknown mutant {n!r}; known: {', '.join(CATALOGUE)}")
    return names


def mutation_values(names) -> dict:
    """The :class:`mcrt.options.Mutations` fields that the mutants ``names`` set, and their values."""
    out: dict = {}
    for n in sorted(check_mutants(names)):
        out.update(CATALOGUE[n].mutations)
    return out


def camera_jitter(names) -> bool:
    """Whether camera samples are jittered over the pixel under the mutants ``names``."""
    return all(CATALOGUE[n].jitter for n in check_mutants(names))


def output_encoding(names) -> str:
    """'linear', or 'srgb' where a mutant writes the image gamma-encoded."""
    return "srgb" if any(CATALOGUE[n].output == "srgb" for n in check_mutants(names)) else "linear"


def mutate_scene(scene: Scene, names) -> Scene:
    """The scene as the mutants ``names`` change it (the scene itself where none does)."""
    for n in sorted(check_mutants(names)):
        if CATALOGUE[n].scene is not None:
            scene = CATALOGUE[n].scene(scene)
    return scene
