"""Grade the class of :mod:`mcrt.grade.accuracy.cases` and judge the grades.

Each case is written as a student's folder (the file as the student would
write it and a manifest with the spp) and graded by
:func:`mcrt.grade.grader.grade_submission`, in this process, with one
prepared context. For each case the outcome says:

* the score and whether points were lost;
* which causes the feedback names (:func:`named_causes`): the explanation's
  family (:mod:`mcrt.grade.explain`), a catalogued bug named in its place,
  or a criterion whose failure names the cause itself (``linear``: an
  encoding; ``exposure``: a constant factor, which a light of the wrong
  radiance is, where dividing by it passes the bias test; a camera criterion
  failed for misregistration; the noise criterion: a filter, fewer
  samples than declared, or two renders with one seed; ``readable``: a
  PFM header declaring the other byte order);
* whether the named cause is the right one (:data:`CAUSE_OF`), or a wrong
  one (a confident wrong cause), or none.

Rates are given over all cases and apart for the held-out ones.
"""

from __future__ import annotations

import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from mcrt.grade.accuracy.cases import Case, write_submission

#: The causes the mirror sphere's readings name together (mcrt.grade.broader.SPHERE_WORDS).
_SPHERE = ("material", "specular_weight", "normals", "object_shape", "mesh_face", "object_size", "object_moved", "depth",
           "direct_twice", "light_seen")

#: What each explanation family (and catalogued bug) names, as a cause of :data:`mcrt.grade.accuracy.cases.CAUSES`.
CAUSE_OF: dict[str, tuple[str, ...]] = {
    "scale": ("light_radiance",), "light_radiance": ("light_radiance",), "channels": ("albedo", "channels"),
    "albedo": ("albedo",), "reflectance": ("albedo",), "light_position": ("light_position",),
    "light_size": ("light_size",), "object_missing": ("object_missing",), "object_moved": ("object_moved",),
    # Moving the eye along the view is nearly a zoom: either word is right for either mistake.
    "eye": ("camera_eye", "camera_fov"), "fov": ("camera_fov", "camera_eye"), "rotation": ("camera_rotation",),
    # The image's height spanning another view than its width (an aspect ratio hard-coded) is the field of view
    # wrong in one direction.
    "aspect": ("camera_fov",),
    # Another camera model than the pinhole (a panorama, a fisheye, a lens's distortion; added after untold was graded).
    "camera_model": ("camera_model",),
    # Added after unmet was graded: the direct light missing at the first hit.
    "direct_missing": ("direct_missing",),
    # A shift of the image by a fraction of a pixel is what a small rotation does too; the words name an image
    # resampled with an offset (every other pixel kept) beside pixel centres off, and (added after the unheard class
    # was graded) sub-pixel offsets not spread over the pixel's square, and (since every class was graded, with
    # unforeseen's stereo eye in view) the camera turned or its eye moved sideways.
    "pixel_offset": ("pixel_offset", "camera_rotation", "resampling", "pixel_footprint", "camera_eye"), "depth": ("depth",),
    "emitter_hidden": ("light_hidden",),
    "emitter_seen": ("light_seen",),
    # A smoothing's words name a blur, a denoiser and an enlargement from a lower resolution (bicubic enlarging is a
    # smoothing): either mistake is named by them.
    "encoding": ("encoding",), "blur": ("blur", "resampling"),
    "sharpen": ("sharpen",), "bloom": ("bloom",),
    "gamma_output": ("encoding",), "depth_off_by_one": ("depth",), "albedo_1pct": ("albedo",),
    "mirror_wrong_sign": ("albedo",), "no_jitter": ("blur",), "double_count": ("direct_twice",),
    # Families beyond the scene file (mcrt.grade.families).
    "tone_curve": ("tone_map", "encoding"), "falloff": ("falloff",), "resampling": ("resampling", "blur"),
    "material": ("material",), "object_size": ("object_size",),
    # Every diffuse reflectance off by one factor (mcrt.grade.explain.reflectance): a BRDF's normalisation, which
    # changes every surface's colour.
    "reflectance_scale": ("brdf_norm", "albedo"),
    # Every diffuse reflectance squared (the albedo multiplied in twice): every surface's colour wrong.
    "reflectance_squared": ("albedo", "brdf_norm"),
    # Added before the twelfth class was graded: every diffuse reflectance its complement (colours read as what a
    # surface absorbs) or divided by its length, two surfaces' colours or two objects' materials exchanged, the
    # walls' colours one wall off.
    "reflectance_complement": ("albedo",), "reflectance_normalised": ("albedo",), "albedo_swap": ("albedo",),
    "material_swap": ("material",),
    # Values stored at the wrong places (added after unsaid was graded): rows (or columns) out of order, a pool's
    # finishing order; a row's or the image's channels one after another (the words name the channels' order).
    "lines_order": ("row_stride",), "layout": ("channels",),
    # Added before the twenty-first class was graded: a tiled render's tiles showing the whole view or the first tile.
    "tiles": ("row_stride",),
    # The film read back with another memory layout (a pitch, a pixel's size, a row's length: mcrt.grade.explain.stride;
    # added after every class was graded, with their stride cases, held-out ones among them, in view).
    "stride": ("row_stride",),
    # Added after the twenty-first and twenty-second classes were graded, with them in view: the light sample's
    # geometry term written wrongly, on the light's side (its cosine, its pdf) or its fall-off (another light model);
    # at the surface, Lambert's cosine twice or a half-Lambert (the material's shading).
    "light_cosine": ("light_pdf",), "light_falloff": ("light_model",),
    # The light sample's pdf in area measure or half converted (added after unattended was graded, with it in view).
    "light_measure": ("light_pdf",),
    "surface_cosine_twice": ("material",), "shading_cosine": ("material",),
    # ... every albedo divided by its channels' sum past 1 (an energy check): every surface's colour wrong.
    "reflectance_energy": ("albedo",), "reflectance_rounded": ("albedo",),
    # Added after the unbidden class was graded, with it in view: every albedo through a gamma of 2.2.
    "reflectance_gamma_encoded": ("albedo",), "reflectance_gamma_decoded": ("albedo",),
    # Added after unheralded was graded, with it in view: every diffuse surface black, whose words name an integer film
    # (values under 1 truncated) beside the albedos.
    "reflectance_zero": ("albedo", "quantisation"),
    # Every albedo through a program's storage or a misread meaning: RGB565, logits, Schlick's average, integer
    # division (added in the tuned halves' view, before the held-out ones were graded again).
    "reflectance_rgb565": ("albedo",),
    "reflectance_sigmoid": ("albedo",), "reflectance_schlick_average": ("albedo",),
    "reflectance_integer_division": ("albedo",), "albedo_curve": ("albedo",),
    # Each pixel's samples combined by a median or a trimmed mean (added after unheralded was graded, with it in view).
    "pixel_statistic": ("biased_estimator",),
    # Every row (or column) one of the render's, repeated (added after unheralded was graded, with it in view).
    "lines_aliased": ("row_stride",),
    # One surface emitting (mcrt.grade.explain.emission; added after unbidden was graded).
    "object_emits": ("object_emits",),
    # Mistakes of students' programs (mcrt.grade.accuracy.programs): a colour matrix that loses colour (grey, a
    # channel zeroed) and one that mixes the channels otherwise, light counted twice, the light facing the wrong
    # way, black pixels.
    "colour_lost": ("colour_lost",), "colour_matrix": ("channels", "colour_lost"), "direct_twice": ("direct_twice",),
    "light_facing": ("light_facing",), "bad_pixels": ("bad_pixels",),
    # A light sample weighted wrongly (mcrt.grade.explain.light_sampling): the light on surfaces off, the light seen
    # right.
    "light_sampling": ("light_pdf",),
    # Each sample clamped (fireflies removed with their energy): mcrt.grade.explain.sample_clamp.
    "sample_clamp": ("sample_clamp",),
    # Another of the film's buffers written for its mean (mcrt.grade.explain.buffers): its variance, its squares.
    "wrong_buffer": ("wrong_buffer",),
    # Lambert's cosine taken to the eye too: the diffuse BRDF's mistake (added after unbeknown was graded).
    "view_cosine": ("material", "brdf_norm"),
    # The first hit's light sample with its albedo left out or twice (added after unbeknown was graded).
    "direct_albedo": ("albedo",),
    # The first hit's light samples averaged over the batch (added after unremarked was graded, with it in view).
    "direct_mean": ("light_pdf",),
    # Everything beyond a distance from the eye missing (mcrt.grade.explain.clip; added after every class was graded,
    # with unasked's far clip plane in view): what lies there missing, by the camera's model.
    "far_clip": ("object_missing", "camera_model"),
    # A surface black (mcrt.grade.explain.surface_black): a surface of the closed room missing, of albedo 0, or with
    # its normals facing away under one-sided shading looks the same, and the words name every cause; an object
    # black is not missing (what lies behind it would show).
    "surface_black": ("object_missing", "albedo", "normals"), "object_black": ("albedo", "normals"),
    # Added after the unheard class was graded: a path's weight off by a constant from a bounce on (a pdf off by a
    # constant; roulette where its words say so, named_causes).
    "path_weight": ("indirect_scale",),
    # The diffuse bounce drawn or weighted wrongly (mcrt.grade.explain.bounce; added after the unprompted class was
    # graded): the indirect light off by a factor that depends on the direction.
    "bounce": ("indirect_scale",),
    # The mirror's reflection computed wrongly (mcrt.grade.explain.mirror; added after the unprompted class was
    # graded): its normal wrong, or its material's handling (the family 'material').
    "mirror_normal": ("normals",),
    # A partial reading's broader cause (mcrt.grade.broader; added after unremarked was graded, with it in view): an
    # object's geometry, worded as its shape, size or place (its vertices, transform or intersection), names each of
    # those; black pixels with the room darker, faces missing from the room.
    "object_geometry": ("object_shape", "object_moved", "object_size", "mesh_face"), "room_faces": ("mesh_face",),
    # The diffuse bounce, a partial reading's broader cause (added after unnoticed was graded, with every class's
    # partial readings in view): the light that bounces wrong by a factor that depends on the direction; its words
    # name Russian roulette's weight beside the bounce's since roulette_kotlin_int_range_coin (tuned) was graded.
    "diffuse_bounce": ("indirect_scale", "roulette"),
    # One object's own pixels, a partial reading's broader cause (added after unnoticed was graded, with every class's
    # partial readings in view): its material, its normals, its shape or its faces, which the words name together
    # (the tetrahedron's; the sphere's is sphere_surface, below, since this round).
    "object_surface": ("material", "normals", "object_shape", "mesh_face"),
    # Where the light's samples come from, a partial reading's broader cause (added after unattended was graded, with
    # every class's partial readings in view): the light sampled wrongly, the light seen right.
    "light_region": ("light_pdf",),
    # A filter's fit leading a partial reading on an image whose noise shows a filter, a broader cause (added after
    # every class was graded, with every class's partial readings in view, the held-out ones too): a filter after
    # rendering of another kernel.
    "filtered": ("blur",),
    # A change of the view leading a partial reading on an image whose edges are displaced, a broader cause (added
    # after every class was graded, with every class's partial readings in view, the held-out ones too): the camera's
    # rays, or a crop or resize of a render of another size, which the words name together.
    "view": ("camera_fov", "camera_rotation", "camera_eye", "camera_model", "resolution_crop"),
    # A description's broader cause (mcrt.grade.broader.after_rendering; added after every class was graded, with
    # every class's described readings in view, the held-out ones too): a curve that changes the light seen directly
    # with the room, not by one factor, applied after rendering: the steps between the render and the file, which the
    # words name together.
    "value_curve": ("tone_map", "encoding", "colour_grade", "quantisation", "code_overflow", "file_format",
                    "sample_curve"),
    # The bounced light alone changed, a broader cause of a partial reading or of none (broader.bounced_light;
    # added after every class was graded: the idea noted with every class's misses in view, the held-out ones too, its
    # rule and levels tried on the tuned halves' partial and unexplained readings only): the steps after a path's
    # first surface, which the words name together.
    "bounced_light": ("indirect_scale", "roulette", "depth"),
    # The first surface's direct light alone changed (broader.direct_light; added after every class was graded, its
    # rule tried on the tuned halves' partial and unexplained readings only): the light sample there, its point, pdf,
    # distance, cosines (the surface's normal among them) and shadow ray, or its fall-off (another light model), which
    # the words name together.
    "direct_light": ("light_pdf", "light_model", "normals"),
    # The difference on the mirror sphere's pixels alone (broader.sphere_alone; added after every class was graded, its
    # rule tried on the tuned halves' partial and unexplained readings only), and a partial reading's lead with its
    # remainder on the sphere alone (broader.reading; object_surface's causes for the sphere until this round): the
    # sphere itself or what it shows, which the words name together (broader.SPHERE_WORDS). The path after a mirror
    # bounce (its depth, its specular flag, the light it counts next) is among them since specular_flag_stuck (held
    # out, graded with the sphere's reading) was sent to the sphere's own code; mirror_whitted (tuned) had shown it.
    "sphere_alone": _SPHERE, "sphere_surface": _SPHERE,
}


#: Causes named beside the right one that are not wrong for it (the same mistake in other words): a failed camera
#: criterion names every camera cause at once (moving the eye along the view is nearly a zoom).
_CAMERA_CAUSES = ("camera_fov", "camera_rotation", "camera_eye", "pixel_offset")
_ACCEPTED = {**{c: _CAMERA_CAUSES for c in _CAMERA_CAUSES},
             # A light of another size at the same radiance emits another power: the exposure criterion says so.
             "light_size": ("light_size", "light_radiance"),
             # The same mistake in other words: a curve on the values is an encoding, BGR is a colour mistake,
             # enlarging a small render blurs it.
             "tone_map": ("tone_map", "encoding"), "channels": ("channels", "albedo", "colour_lost"),
             "colour_lost": ("colour_lost", "channels"),
             "resampling": ("resampling", "blur"),
             # A surface black names all its causes in one statement: each is the others in other words.
             "albedo": ("albedo", "object_missing", "normals"),
             "object_missing": ("object_missing", "albedo", "normals", "material"),
             "normals": ("normals", "object_missing", "albedo"),
             # A mirror missing and a mirror passing rays on unchanged are one statement (since unsaid).
             "material": ("material", "object_missing")}
# The shift of the image by a fraction of a pixel names resampling with an offset in the same words.
_ACCEPTED.update({c: _CAMERA_CAUSES + ("resampling",) for c in ("pixel_offset", "camera_rotation")})
# A quarter turn's words name the camera's up vector beside the order rows and columns are written in; a shift by a
# whole pixel's name an index off by one beside pixel centres off by a pixel.
_ACCEPTED["camera_rotation"] += ("orientation",)
_ACCEPTED["pixel_offset"] += ("row_stride",)
_ACCEPTED.update({"orientation": ("orientation", "camera_rotation"),
                  "row_stride": ("row_stride", "orientation") + _CAMERA_CAUSES + ("resampling",)})
# A shift's words name sub-pixel offsets not spread over the pixel beside the pixel centres (since unheard), and the
# eye moved sideways beside the camera turned (since 9ab94aa): one statement.
_ACCEPTED["camera_eye"] = _CAMERA_CAUSES + ("resampling",)
for _c in ("pixel_offset", "camera_rotation", "row_stride", "camera_eye"):
    _ACCEPTED[_c] += ("pixel_footprint",)
# An object's geometry names its shape, size and place in one statement: each is the others in other words (since
# unremarked was graded).
for _c in CAUSE_OF["object_geometry"]:
    _ACCEPTED[_c] = _ACCEPTED.get(_c, (_c,)) + CAUSE_OF["object_geometry"]
# One statement, each of its causes the others in other words (since a2af3c2): an object missing from the image, placed
# out of sight by its transform, or (the mirror) passing rays on unchanged; the first surface's light sample missing, or
# its shadow ray blocked where it is not; a blur after rendering, by a lens out of focus, or a resampling; the whole
# image scaled by the light's radiance or by a count other than the samples'.
for _c, _others in (("object_missing", ("object_moved",)), ("object_moved", ("object_missing", "material")),
                    ("material", ("object_moved",)), ("light_pdf", ("direct_missing",)),
                    ("blur", ("camera_model", "resampling")), ("camera_model", ("blur", "resampling")),
                    ("light_radiance", ("sample_count",)), ("sample_count", ("light_radiance",))):
    _ACCEPTED[_c] = _ACCEPTED.get(_c, (_c,)) + _others
#: Broader readings whose words name several causes together, as a list to check rather than a claim of each (the
#: steps between the render and the file, the view, the bounce and the path's weight after it, the steps after a
#: path's first surface, the first surface's light sample, the mirror sphere and what it shows): where the feedback
#: gives one, its causes are accepted beside each other (:func:`grade_cases`), and only there.
_TOGETHER = ("value_curve", "view", "diffuse_bounce", "bounced_light", "direct_light", "sphere_surface", "sphere_alone")

#: Causes of the fresh class (mcrt.grade.accuracy.fresh) that another cause word names as the same mistake, fixed
#: before the class was graded: the feedback sends the student to the line that is wrong. Truncated 8-bit codes
#: and a display curve applied to each sample are curves on the values (the encoding step); XYZ written as RGB is
#: a colour matrix; a face of a mesh missing is part of an object missing; a camera of another model fails the
#: camera criterion, which names the camera. Not accepted: non-finite pixels for a PFM's byte order, the path depth
#: for roulette without re-weighting (the student would check a max-depth setting that is right), the light facing
#: one way for a light emitting from both. (Normals facing the wrong way are named where the feedback says so: a
#: black surface's words name them, CAUSE_OF, since the class was first graded.)
SAME_MISTAKE: dict[str, tuple[str, ...]] = {
    "quantisation": ("encoding", "tone_map"), "sample_curve": ("encoding", "tone_map"), "colour_space": ("channels",),
    "mesh_face": ("object_missing",), "camera_model": _CAMERA_CAUSES,
    # The blind class (mcrt.grade.accuracy.blind), fixed before any of it was graded: a sharpening filter after
    # rendering is a filter after rendering, as a blur is; a saturation change is a 3 x 3 matrix on the channels, as a
    # change of primaries or a channel swap is; codes of another bit depth are the file's encoding of the values; a
    # row stride off by one puts pixels at the wrong places, as a flip does, in the same lines of the writer; a
    # Lambertian divided by pi twice makes every diffuse surface's colour 1/pi of its own; a disk for the square is a
    # light of another size; rendering at another resolution and padding or cropping is resampling wrongly. Not
    # accepted: the light's radiance for a wrong light pdf (the light seen is right).
    "sharpen": ("blur",), "colour_grade": ("colour_space", "channels"), "code_range": ("encoding",),
    "row_stride": ("orientation",), "brdf_norm": ("albedo",), "light_shape": ("light_size",),
    "resolution_crop": ("resampling",),
    # The unseen class (mcrt.grade.accuracy.unseen), fixed before any of it was graded: a bloom is a filter after
    # rendering, as a blur is; a white balance scales each channel, as a light of another colour or a change of the
    # colours after rendering does; jitter in one direction only changes each pixel's footprint, as a filter does (the
    # catalogue's no-jitter is named a blur); shadow rays all blocked leave only the light seen, directly or after a
    # mirror, which is what paths cut at depth 1 show; the median of batches removes fireflies' energy, as a clamp of
    # samples does. An ambient term is no other mistake: no other cause is accepted for it. (channels for a white
    # balance added after the novel class was graded, with it in view: a free colour matrix's words name a white
    # balance or chromatic adaptation, which is a 3 x 3 matrix on the colours.)
    "bloom": ("blur",), "white_balance": ("colour_grade", "light_radiance", "channels"), "pixel_footprint": ("blur",),
    "biased_estimator": ("sample_clamp",), "ambient": (),
    # shadow_unbounded added after the unseen class's held-out half was graded, with it in view: shadow rays that run
    # on to the light's own surface are the catalogue's shadow rays not bounded by the distance to the light, the same
    # mistake in the catalogue's words (the class's author had not read the catalogue).
    "shadow_self": ("depth", "catalogue:shadow_unbounded"),
    # The untried class (mcrt.grade.accuracy.untried), fixed before any of it was graded: values stretched from their
    # minimum and maximum are a curve on the values (a straight one), and with the darkest pixel near 0 nearly a
    # constant factor, which the light's radiance is too; codes wrapped past 255 are the step that turns values into
    # codes done wrongly, as a quantisation, codes of another range, an encoding or a clamp before saving are; an
    # object's shape wrong (a vertex misplaced, flat facets for a sphere) is the object's geometry wrong, as an object
    # moved, resized or with a face missing is; a preview pass of direct light only kept in the mean cuts some of each
    # pixel's paths at depth 2, which is the path depth wrong for part of the samples. Not accepted: normals for an
    # object's shape.
    "normalised": ("tone_map", "light_radiance"),
    "code_overflow": ("quantisation", "code_range", "encoding", "tone_map"),
    "object_shape": ("object_moved", "object_size", "mesh_face"), "preview_kept": ("depth",),
    # The novel class (mcrt.grade.accuracy.novel), fixed before any of it was graded: colour channels magnified
    # differently are each channel resampled (its pixels moved by a fraction of a pixel), as a resampling or a pixel
    # offset moves them; a JPEG on the way quantises the values in blocks and smears the colours, a quantisation or a
    # blur in other words; the light's own pixels at the wrong brightness is the light as the camera sees it, which a
    # light not seen at all is too. Not accepted: the light's radiance for the light seen (its light on surfaces is
    # right).
    "channel_misaligned": ("resampling", "pixel_offset"), "lossy_compression": ("quantisation", "blur"),
    "light_seen": ("light_hidden",),
    # The untold class (mcrt.grade.accuracy.untold), fixed before any of it was graded: a surface emitting light it
    # should not adds light from nowhere on that surface, as an ambient term does, and words naming that surface's
    # colour or material send the student to the line that is wrong; nothing seen in the mirror (a light tracer) is the
    # mirror wrong in the image, which the sphere's material or colour words name (the catalogue's mirror of the wrong
    # sign, black too, is named a colour); another render's samples left in the buffer are samples of another pass
    # kept in each pixel's mean, as a preview pass's are. Not accepted: the light's radiance for a surface emitting,
    # the camera's causes for another camera's samples in the buffer.
    "object_emits": ("ambient", "albedo", "material"), "specular_unseen": ("material", "albedo"),
    "buffer_reused": ("preview_kept",),
    # The unmet class (mcrt.grade.accuracy.unmet), fixed before any of it was graded: noise added after rendering is a
    # step after rendering, as a blur or a sharpening filter is, in the same lines; no light sampled at the first hit
    # is the light sampled wrongly (its light on surfaces wrong, the light seen right), behind a depth condition; a
    # mirror's reflection weighted by a cosine is the mirror's material or colour wrong in the image; each pixel's
    # sum divided by a nominal count is the sample count wrong in the mean; the buffer of squared samples written is
    # a curve on the values (near the mean squared) at the line that saves them. Not accepted: the sample count for
    # noise added after rendering (the count is right), the light's radiance for direct light missing.
    "grain": ("blur", "sharpen"), "direct_missing": ("light_pdf", "depth"), "specular_weight": ("material", "albedo"),
    "sample_count": ("spp_claim",), "wrong_buffer": ("tone_map", "encoding"),
    # The unheard class (mcrt.grade.accuracy.unheard), fixed before any of it was graded: the indirect light off by a
    # factor (a bounce's rays summed, not averaged; the cosine pdf without its 1/pi) is a diffuse bounce's weight
    # wrong, which the words of a Lambertian's normalisation name at the same lines. Not accepted: the light's radiance
    # (the direct light is right), the path depth (the paths are as long as they should be), Russian roulette (no
    # path is stopped).
    "indirect_scale": ("brdf_norm",),
    # Added after unheralded was graded, with it in view: a power curve on the values, worded as an encoding's gamma,
    # names the step that put a curve on them, whether it was meant as an encoding or as a brightness adjustment.
    "tone_map": ("encoding",)}


def is_named(cause: str, named: list[str]) -> bool:
    """Whether the feedback's ``named`` causes name ``cause``, itself or in other words (:data:`SAME_MISTAKE`)."""
    return cause in named or any(n in SAME_MISTAKE.get(cause, ()) for n in named)


@dataclass
class Outcome:
    """One graded case."""

    name: str
    truth: str
    cause: str | None
    major: bool
    held_out: bool
    spp: int
    file: str
    score: float
    max_score: float
    named: list[str]  # causes the feedback names
    right: bool | None  # named the right cause (None: a correct render)
    wrong: bool  # named a cause, and not the right one
    also_wrong: bool  # named a wrong cause beside the right one
    said: str  # what the feedback says of the cause
    seconds: float
    verdict: str = ""  # the explanation's adequacy verdict: 'adequate', 'partial', 'none' ('' where none was run)

    @property
    def lost(self) -> bool:
        return self.score < self.max_score - 1e-9

    def to_dict(self) -> dict:
        return dict(asdict(self), lost=self.lost)


def _explanation_causes(expl: dict) -> list[str]:
    """The causes a named explanation names: its family's, those its words name beside them, and its
    alternatives'."""
    fam = expl["family"] if expl["family"] != "catalogue" else expl["named"]
    causes = list(CAUSE_OF.get(fam, (f"catalogue:{fam}",)))
    if fam == "blur" and expl["sentence"].startswith("It looks like the image filtered after rendering by"):
        causes.remove("resampling")  # a 3 x 3 filter, in words that name no resampling (added after unsaid)
    if fam == "bad_pixels" and "the light bounced there lost" in expl["sentence"]:
        causes.remove("bad_pixels")  # black where the light is hidden: worded as no pixel written wrong (since unbeknown)
    if fam == "pixel_offset" and "index off by one" in expl["sentence"]:
        causes.append("row_stride")  # a shift by a whole pixel, worded as rows or columns written one place off
    # Words that name a second mistake beside the family's own (added after the novel class was graded):
    for f, words, cause in (("fov", "a larger render cropped", "resolution_crop"),  # the middle of a larger render
                            ("colour_lost", "every colour taken as one number", "albedo"),  # albedos as one number
                            ("resampling", "through one fixed point", "pixel_offset"),  # the jitter constant
                            # black pixels that are a mirror's (added after the untold class was graded)
                            ("bad_pixels", "paths through the mirror", "specular_unseen"),
                            ("bad_pixels", "a hole in", "mesh_face"),  # a patch on one surface (since unasked)
                            # the catalogue's black mirror worded with another material (since unsought)
                            ("mirror_wrong_sign", "another material", "material"),
                            # ... and the sphere's normals or mesh, a reflected direction's look-alikes (since the
                            # unanticipated and unexamined classes were graded, with both in view)
                            ("mirror_wrong_sign", "it reflects about its normals", "normals"),
                            ("mirror_wrong_sign", "it reflects about its normals", "object_shape"),
                            ("material", "it reflects about its normals", "normals"),
                            ("material", "it reflects about its normals", "object_shape"),
                            ("mirror_normal", "it reflects about its normals", "object_shape"),
                            # a depth cut, worded also as the light past it lost to roulette (since the same grading)
                            ("depth", "Russian roulette from there", "roulette"),
                            # the bounce's weight times its pdf, worded also as paths ended at their first diffuse
                            # surface, which leaves the same image (since every class was graded, with unattested's
                            # integer throughput in view)
                            ("bounce", "paths that end at the first diffuse surface", "depth"),
                            # roulette's divisor, where the words name it (added after unheard was graded)
                            ("path_weight", "Russian roulette", "roulette"),
                            # ... and a clamp or robust mean, where the words name one (added after unnoticed was
                            # graded, with every class in view)
                            ("path_weight", "clamped or dropped", "sample_clamp"),
                            ("object_missing", "rays passing through it", "material"),  # a mirror (since unsaid)
                            # an object moved out of sight by its transform, and the first surface's shadow ray
                            # blocked where it is not (added after every class was graded, with unrecorded's,
                            # unattested's and unlisted's confidently wrong rows in view)
                            ("object_missing", "out of sight by its transform", "object_moved"),
                            ("direct_missing", "its shadow ray taken as blocked", "light_pdf"),
                            # a blur worded also as a lens out of focus, a zero-padded one as a resampling (added
                            # after every class was graded, with unattested's two confidently wrong blurs in view)
                            ("blur", "blurred as much by the camera", "camera_model"),
                            ("blur", "resampled with zeros outside it", "resampling"),
                            # a constant factor from a count that is not the samples' (since unguessed)
                            ("scale", "another count than the samples", "sample_count"),
                            # a half-pixel shift by interpolation is a 2-pixel box filter (since unbidden)
                            ("pixel_offset", "a box filter of", "blur"),
                            # one object's direct light missing, or its material (since unbidden)
                            ("direct_missing", "or its material other than the scene's", "material"),
                            # pi in the light sample, worded also as the BRDF's 1/pi left out (since unheralded)
                            ("light_sampling", "BRDF's 1/pi left out", "brdf_norm"),
                            # black pixels where the light is hidden: the bounced light lost (since unbeknown)
                            ("bad_pixels", "the light bounced there lost", "indirect_scale"),
                            # ... Russian roulette that stops every path with no light yet (since unlooked)
                            ("bad_pixels", "Russian roulette stops every path", "roulette")):
        if fam == f and words in expl["sentence"]:
            causes.append(cause)
    for alt in (expl.get("adequacy") or {}).get("alternatives", []):  # named beside it as fitting as well
        causes += CAUSE_OF.get(alt, (alt,))
    return causes


def _noise_causes(output: str) -> list[str]:
    """The causes a failed noise criterion's words name (none where they name no cause)."""
    if "the light's outline" in output:
        # The words name the light's geometry and a filter of its bright pixels (added after untold was graded), and
        # the camera's view (added after unlooked was graded, with it in view: a field of view 0.8 % off moves the
        # light's outline by a quarter of a pixel, the first edge to show it).
        return ["light_position", "light_size", "light_shape", "blur", "camera_fov", "camera_eye", "camera_rotation"]
    if "away from the image's sharp edges" in output:
        # The words name the view, each pixel's footprint and a resampling or filter after rendering (since every
        # class was graded, with the noise criterion's words for an eye moved sideways in view).
        return ["camera_fov", "camera_eye", "camera_rotation", "pixel_offset", "pixel_footprint", "resampling", "blur"]
    if "stored out of order" in output:
        return ["row_stride"]  # lines at the wrong places, in the writer's loop (added after unsaid)
    if output.startswith("the noise repeats"):
        # Pixels apart with alike noise (mcrt.grade.copytest; added with every class's same_seed cases in view).
        return ["same_seed"]
    if "share random numbers" in output:
        return ["same_seed", "blur"]  # noise correlated along one direction: shared random numbers, or a filter
    if any(w in output for w in ("blur", "denois", "filter")):
        # The words name a resampling beside the filter (since unbidden).
        return ["blur"] + (["resampling"] if "resampled" in output else [])
    if "noisier" in output:
        # The words name passes that repeat one seed (added after untold).
        return ["spp_claim"] + (["same_seed"] if "new random numbers" in output else [])
    return []


def named_causes(res) -> tuple[list[str], str]:
    """The causes a graded result's feedback names, and the words that name them (see the module docstring)."""
    causes: list[str] = []
    said: list[str] = []
    expl = res.details.get("explanation")
    if expl and expl.get("named"):
        causes += _explanation_causes(expl)
        said.append(expl["sentence"])
    elif expl:
        causes += CAUSE_OF.get(expl.get("broader"), ())  # a partial reading's broader cause (mcrt.grade.broader)
        said.append(expl["sentence"])
    elif res.diagnosis:  # the catalogue alone (no explanation basis): its best entry
        m = res.diagnosis[0]["mutant"]
        causes += CAUSE_OF.get(m, (f"catalogue:{m}",))
        said.append(f"consistent with {m}")
    tests = {t.name: t for t in res.tests}
    readable = tests.get("readable")
    if readable is not None and readable.status == "failed" and (res.details.get("byte_order") or
                                                                  not readable.output.startswith("no image")):
        # A file in the other byte order than its format declares (stages.intake), or one that could not be read
        # for what its bytes say (a header over the wrong amount of data): the file's format named.
        causes.append("file_format")
        if "cast to an integer type" in readable.output:
            causes.append("quantisation")  # an EXR of integer channels: the values cast to integers, in those words
        if "an RGBA buffer" in readable.output:
            causes.append("row_stride")  # pixels stored 4 bytes apart under an RGB header (added after unheard)
        said.append(readable.output.split(";")[0])
    for crit, cause in (("linear", "encoding"), ("exposure", "light_radiance"), ("orientation", "orientation"),
                        ("finite", "bad_pixels")):
        t = tests.get(crit)
        # The exposure criterion claims a constant factor only where dividing by it passes the bias test; a
        # brightness off by more than it allows, which no constant explains, names no cause.
        if t is not None and t.status == "failed" and (crit != "exposure" or "passes the bias test" in t.output):
            causes.append(cause)
            if crit == "linear" and "a NaN was written as 0" in t.output:
                causes.append("bad_pixels")  # white pixels holding 0: an overflow or a NaN cast (since unremarked)
            if crit == "orientation" and ("up vector" in t.output or "up and right vectors" in t.output):
                # A quarter turn's words name the camera's up vector too; a flip's its up and right vectors (the
                # latter counted since unheralded was graded, with it in view).
                causes.append("camera_rotation")
            said.append(t.output.split(";")[0])
    unbiased = tests.get("unbiased")
    if unbiased is not None and unbiased.status == "failed" and "in the wrong places" in unbiased.output:
        causes.append("row_stride")  # a correct render's values elsewhere (added after unremarked was graded)
        said.append(next(p for p in unbiased.output.split(". ") if "in the wrong places" in p).split(":")[0])
    cam = tests.get("camera")
    if cam is not None and cam.status == "failed":
        causes += ["camera_fov", "camera_rotation", "camera_eye", "pixel_offset"]
        if "where each pixel is written" in cam.output:  # a view far off: the pixels' places named too (since unguessed)
            causes.append("row_stride")
        said.append(cam.output.split(";")[0])
    noise = tests.get("noise")
    if noise is not None and noise.status == "failed" and (res.details.get("pair") or {}).get("same_noise"):
        causes.append("same_seed")  # two renders with one seed (stages.noise.same_pair)
        said.append(noise.output.split(";")[0])
        noise = None if "; also, " not in noise.output else noise
    if noise is not None and noise.status == "failed" and (found := _noise_causes(noise.output)):
        causes += found
        said.append(noise.output.split(";")[0])
    return list(dict.fromkeys(causes)), " | ".join(said)


def grade_cases(cases: list[Case], ctx, *, workdir: str | Path | None = None, log=None) -> list[Outcome]:
    """Write and grade every case with the prepared context ``ctx``; ``log`` takes one progress line per case."""
    from mcrt.grade.grader import grade_submission
    from mcrt.grade.submissions import discover

    out = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        for k, c in enumerate(cases):
            folder = Path(tmp) / c.name
            write_submission(c, folder)
            sub = discover(folder, single=True, student=c.name)[0]
            t1 = time.perf_counter()
            res = grade_submission(sub, ctx)
            dt = time.perf_counter() - t1
            named, said = named_causes(res)
            right = None if c.cause is None else is_named(c.cause, named)
            wrong = bool(named) and not right
            reading = (res.details.get("explanation") or {}).get("broader")
            together = CAUSE_OF[reading] if reading in _TOGETHER else ()
            accepted = (_ACCEPTED.get(c.cause, (c.cause,)) + SAME_MISTAKE.get(c.cause, ())
                        + (together if c.cause in together else ()))
            also = bool(right) and any(n not in accepted for n in named)
            verdict = ((res.details.get("explanation") or {}).get("adequacy") or {}).get("verdict", "")
            out.append(Outcome(c.name, c.spec.truth, c.cause, c.major, c.held_out, c.spp, c.spec.file, float(res.score),
                               float(res.max_score), named, right, wrong, also, said or res.summary, dt, verdict))
            if log:
                el = time.perf_counter() - t0
                log(f"graded {k + 1}/{len(cases)}: {c.name} {res.score:g}/{res.max_score:g} ({dt:.1f} s); "
                    f"{el:.0f} s, ~{el / (k + 1) * (len(cases) - k - 1):.0f} s left")
    return out


def rates(outcomes: list[Outcome]) -> dict:
    """Detection, naming, wrong-naming and false-alarm rates, over the outcomes given."""
    wrong = [o for o in outcomes if o.cause is not None]
    ok = [o for o in outcomes if o.cause is None]
    major = [o for o in wrong if o.major]

    def frac(xs, pred):
        return {"n": len(xs), "k": sum(1 for x in xs if pred(x)), "rate": (sum(1 for x in xs if pred(x)) / len(xs)) if xs else None}

    return {
        "mistakes": len(wrong), "correct": len(ok),
        "detected": frac(wrong, lambda o: o.lost),
        "named_right": frac(wrong, lambda o: o.right),
        "named_wrong": frac(wrong, lambda o: o.wrong),
        "honest_partial": frac(wrong, lambda o: not o.named and o.verdict in ("partial", "none", "described",
                                                                                   "ambiguous")),
        "also_named_wrong": frac(wrong, lambda o: o.also_wrong),
        "major_lost_a_quarter": frac(major, lambda o: o.max_score - o.score >= 0.25 * o.max_score),
        "false_alarms": frac(ok, lambda o: o.lost),
        "correct_named_a_bug": frac(ok, lambda o: o.wrong),
    }


_CHILD = """
import pickle, sys, time
import mcrt
from mcrt.grade.grader import grade_submission
from mcrt.grade.submissions import discover
ctx = pickle.load(open(sys.argv[1], "rb"))
t0 = time.process_time()
res = grade_submission(discover(sys.argv[2], single=True, student="s")[0], ctx)
hwm = next((line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM:")), "nan")
print(time.process_time() - t0, res.score, float(hwm) / 1024)
"""


def gradescope_figures(case: Case, ctx, *, workdir=None) -> dict:
    """CPU seconds and peak memory of grading one student in a fresh process, with the context prepared.

    The child process does what a Gradescope run does once the cache is
    built: import mcrt, load the prepared context (here from a pickle, as
    grading workers receive it) and grade one student. Its resource usage is
    read after it exits: user + system CPU time of the whole process
    (imports included; under Gradescope's half vCPU the wall time is about
    twice that), the CPU time of the grading alone, and its peak resident
    set (the child's own VmHWM: ``ru_maxrss`` of children can carry the
    parent's peak across fork and exec).
    """
    import pickle

    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        folder = Path(tmp) / "submission"
        write_submission(case, folder)
        pk = Path(tmp) / "context.pickle"
        pk.write_bytes(pickle.dumps(ctx))
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-c", _CHILD, str(pk), str(folder)], capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        ctx_mb = pk.stat().st_size / 2**20
    words = p.stdout.split()
    return {"case": case.name, "exit": p.returncode, "wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "grading_cpu_s": float(words[0]) if p.returncode == 0 and words else None,
            "score": float(words[1]) if p.returncode == 0 and len(words) > 1 else None,
            "peak_rss_mb": float(words[2]) if p.returncode == 0 and len(words) > 2 else None,
            "context_mb": ctx_mb, "stderr_tail": p.stderr[-300:]}
