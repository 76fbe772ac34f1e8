"""The registry of families the engine fits (:data:`FAMILIES`), and how the scoring stage weighs them."""

from __future__ import annotations

from mcrt.grade.explain.albedo_curve import albedo_curve
from mcrt.grade.explain.aov import aov
from mcrt.grade.explain.basis import Basis, prepare_basis
from mcrt.grade.explain.bloom import bloom
from mcrt.grade.explain.bounce import bounce
from mcrt.grade.explain.buffers import wrong_buffer
from mcrt.grade.explain.camera import camera, plane_width
from mcrt.grade.explain.catalogue import catalogue
from mcrt.grade.explain.clip import clip
from mcrt.grade.explain.colour import colour
from mcrt.grade.explain.direct_albedo import direct_albedo
from mcrt.grade.explain.direct_mean import direct_mean
from mcrt.grade.explain.curves import curves
from mcrt.grade.explain.emission import emission
from mcrt.grade.explain.falloff import falloff
from mcrt.grade.explain.layout import layout
from mcrt.grade.explain.light_facing import light_facing
from mcrt.grade.explain.light_geometry import light_geometry
from mcrt.grade.explain.light_sampling import light_sampling
from mcrt.grade.explain.light_twice import light_twice
from mcrt.grade.explain.mirror import mirror
from mcrt.grade.explain.objects import material, object_size
from mcrt.grade.explain.path_weight import path_weight
from mcrt.grade.explain.pixel_statistic import pixel_statistic
from mcrt.grade.explain.pixels import bad_pixels
from mcrt.grade.explain.reflectance import REMAPS, reflectance_remapped, reflectance_scale
from mcrt.grade.explain.resampling import resampling
from mcrt.grade.explain.sample_clamp import sample_clamp
from mcrt.grade.explain.scene import albedo, albedos, rendered, scale
from mcrt.grade.explain.stride import stride
from mcrt.grade.explain.surface_black import surface_black
from mcrt.grade.explain.swap import swap
from mcrt.grade.explain.tonecurve import tone_curve
from mcrt.grade.explain.view_cosine import view_cosine
from mcrt.grade.explain.walls import walls_one_colour
from mcrt.mutants import CATALOGUE

#: Every family the engine fits, in this order (ties keep it). The scene file's parameters (and the colours mixed by a
#: matrix, several surfaces' colours at once, every wall one colour, a surface of the room black, the camera and its
#: image plane's width taken wrongly) and the catalogue; then what a student's program gets wrong beyond the scene file
#: (a tone curve, each sample clamped, a fall-off, resampling, bloom, an object's material or size, values stored at the
#: wrong places or read back with another memory layout, colours or materials given to the wrong surfaces, every diffuse
#: reflectance off by one factor, squared or its complement, every colour through one rule, light counted twice, a
#: path's weight off from a bounce on, the diffuse bounce drawn or weighted wrongly, the mirror's reflection computed
#: wrongly, a light sample's weight, the light facing the wrong way, surfaces emitting, each pixel's samples combined by
#: a median or trimmed mean, black pixels, another of the film's buffers written, an auxiliary buffer written,
#: everything beyond a distance from the eye missing, Lambert's cosine taken to the eye too, the first hit's light
#: sample with its albedo left out or twice, or averaged over the batch, the light sample's geometry term written
#: wrongly).
FAMILIES = (scale, colour, curves, albedo, albedos, walls_one_colour, surface_black, rendered, camera, plane_width,
            catalogue, tone_curve, sample_clamp, falloff, resampling, layout, stride, bloom, material, object_size,
            swap, reflectance_scale, reflectance_remapped, albedo_curve, light_twice, path_weight, bounce, mirror,
            light_sampling, light_facing, emission, pixel_statistic, bad_pixels, wrong_buffer, aov, clip, view_cosine,
            direct_albedo, direct_mean, light_geometry)

#: The families that are mistakes of the camera (what the misregistration test of mcrt.grade.structure also sees).
CAMERA_FAMILIES = frozenset({"fov", "aspect", "pixel_offset", "rotation", "eye", "camera_model"})
#: The families a TA counts as major mistakes whatever their share of the image: the camera, the scene's geometry
#: (an object or the light missing, moved or resized) and its colours (mcrt.grade.scoring.unbiased_loss).
MAJOR_FAMILIES = CAMERA_FAMILIES | {"object_missing", "object_moved", "light_position", "light_size", "albedo", "channels",
                                    "material", "mirror_normal", "object_size", "colour_lost", "light_facing",
                                    "surface_black", "object_black", "reflectance_scale", "reflectance_squared",
                                    "reflectance_complement", "reflectance_normalised", "reflectance_rounded",
                                    "reflectance_energy",
                                    "reflectance_gamma_encoded", "reflectance_gamma_decoded", "reflectance_zero",
                                    "reflectance_rgb565", "reflectance_sigmoid",
                                    "reflectance_schlick_average", "reflectance_integer_division", "albedo_curve",
                                    "albedo_swap", "material_swap", "object_emits", "view_cosine", "far_clip"}


#: The families whose change leaves each sample's noise as the reference's wherever it leaves the mean: a scale, curve
#: or matrix on the values, the scene's colours, the camera's view. Beside a claim of any other (the geometry, the
#: light, how samples are drawn, weighted or combined) the noise is not judged (:func:`keeps_noise`): such a mistake
#: makes noise of its own where the mean hardly moves (the caustics of a larger mirror, light samples drawn off the
#: light), which is no sign of fewer samples.
NOISE_KEPT = CAMERA_FAMILIES | {"scale", "light_radiance", "channels", "colour_lost", "colour_matrix", "encoding",
                                "tone_curve", "falloff", "albedo", "albedo_swap", "surface_black", "object_black",
                                "reflectance_scale", "albedo_curve"} | {family for family, _, _ in REMAPS}


def keeps_noise(c) -> bool:
    """Whether the candidate ``c``'s change leaves each sample's noise alone where it leaves the mean
    (:data:`NOISE_KEPT`); of the catalogue, a bug of the camera's jitter, the output or the scene, not the estimator."""
    return not CATALOGUE[c.name].mutations if c.catalogue else c.family in NOISE_KEPT


def prepare(a, scene, render) -> Basis:
    """The basis of :func:`~mcrt.grade.explain.basis.prepare_basis`, with what each family renders for itself.

    A family with a ``prepare(a, scene, render)`` attribute (optional in
    :class:`mcrt.grade.candidates.Family`) gets its result in
    ``Basis.extra[family.name]``; ``render(scene, camera, width, height,
    max_depth, spp, seed)`` is the grading cache's render, as for the basis.
    """
    b = prepare_basis(a, scene, render)
    for family in FAMILIES:
        own = getattr(family, "prepare", None)
        if own is not None:
            b.extra[family.name] = own(a, scene, render)
    return b
