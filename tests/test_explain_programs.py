"""Families of mistakes a student's program makes beyond the scene file (issue 27): colour lost or mixed, light
counted twice, the light facing the wrong way, black pixels, a surface of the room black, and the image's
orientation.

Every hand-in is a **Mitsuba** render (an edited scene, or a render post-processed with NumPy as a student's program
would), never the grader's own model image nor a case of mcrt.grade.accuracy.programs. The context is the 32x32
course assignment of test_diagnose, prepared once per module in the run's cache; every render names its seed, and
the levels are the production ones. Each family must claim its cause on its mistake and claim nothing on a correct
render and on another mistake.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial

import numpy as np
import pytest
from test_diagnose import ASSIGNMENT, RES

from mcrt.grade.accuracy.cases import Spec, _render_spec, wall_albedo
from mcrt.grade.accuracy.run import named_causes
from mcrt.grade.assignment import assignment_from_dict
from mcrt.grade.expected import prepare_context
from mcrt.grade.grader import grade_image
from mcrt.scene import load_scene

#: The causes the families added here name (mcrt.grade.accuracy.run.CAUSE_OF), besides albedo.
NEW = ("colour_lost", "channels", "direct_twice", "light_facing", "bad_pixels", "object_missing", "orientation")


@pytest.fixture(scope="module")
def ctx(tmp_path_factory, grade_cache):
    a = assignment_from_dict(ASSIGNMENT, str(tmp_path_factory.mktemp("programs") / "explain32.toml"))
    return prepare_context(a, grade_cache)


def _mitsuba(seed: int, scene=None, **spec) -> np.ndarray:
    spec = {"spp": 1024, **spec}
    r = _render_spec(Spec("t", None, **spec), scene or load_scene(), width=RES, height=RES, max_depth=8, seed=seed)
    return np.asarray(r.mean, np.float64)


def _mitsuba_direct(seed: int, spp: int = 1024) -> np.ndarray:
    """Mitsuba's direct-lighting integrator with the light itself hidden (what a direct pass adds)."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    d = scene_dict(load_scene(), "near", RES, RES, 8, spp=spp)
    d["integrator"] = {"type": "direct", "hide_emitters": True}
    return np.asarray(render_with_variance(d, spp=spp, seed=seed).mean, np.float64)


def _claimed(res) -> tuple[str | None, str]:
    ex = res.details.get("explanation") or {}
    return (ex.get("family") if ex.get("verdict") == "claimed" else None), ex.get("sentence", res.summary)


@pytest.mark.parametrize("name, post, family, what", [
    ("grey", lambda x: np.repeat((x @ np.array([0.2126, 0.7152, 0.0722]))[..., None], 3, axis=2), "colour_lost",
     "grey Rec. 709"),
    ("blue_zeroed", lambda x: x * np.array([1.0, 1.0, 0.0]), "colour_lost", "blue zeroed"),
    ("bgr", lambda x: x[..., ::-1], "channels", "channels BGR"),
])
def test_a_colour_matrix_is_named(ctx, name, post, family, what):
    """A Mitsuba render (seed 61) written as luminance in every channel, with blue written as 0, and in BGR order:
    claimed by the matrix that was applied, with a scale of about 1; the image loses points."""
    res = grade_image(name, ctx, [post(_mitsuba(61))], spp=1024)
    fam, said = _claimed(res)
    assert fam == family and res.details["explanation"]["named"] == what, said
    assert res.details["explanation"]["candidates"][0]["value"]["scale"] == pytest.approx(1.0, abs=0.03)
    assert res.score < res.max_score


def test_the_display_curve_on_two_channels_is_named_per_channel(ctx):
    """A Mitsuba render (seed 61) written to an 8-bit sRGB file with the curve applied to red and green only, blue
    written as linear codes (a loop over range(2)): read back, red and green are right and blue is decoded once more.
    Claimed as the display curve per channel, in those words; the image loses points."""
    from mcrt.image_files import srgb_eotf

    x = np.clip(_mitsuba(61), 0.0, 1.0)
    res = grade_image("srgb_rg", ctx, [np.concatenate([x[..., :2], srgb_eotf(x[..., 2:])], axis=-1)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "encoding" and res.details["explanation"]["named"] == "sRGB curve per channel", said
    assert "red and green right; blue written linear" in said
    assert res.score < res.max_score


def test_a_display_curve_on_a_noisy_render_is_named(ctx, tmp_path):
    """stbi_write_hdr called on the film after it was sRGB-encoded and clipped in place for the PNG: unrecorded's maker
    (tuned half; a Mitsuba render at 256 spp, written as a Radiance picture). The curve is steep near black, where
    it grows the render's noise several times over, which the remainder test allows
    (mcrt.grade.explain.fit.bent_noise): claimed as the sRGB curve, clipped, not only described as a curve; the
    image loses points."""
    from mcrt.grade.accuracy import unrecorded
    from mcrt.grade.accuracy.cases import write_submission
    from mcrt.grade.grader import grade_submission
    from mcrt.grade.submissions import discover

    c = _tuned(unrecorded, "file_stbi_hdr_display_buffer")
    write_submission(c, tmp_path / c.name)
    res = grade_submission(discover(tmp_path / c.name, single=True, student=c.name)[0], ctx)
    fam, said = _claimed(res)
    assert fam == "encoding" and "clipped to 1" in said, said
    assert res.score < res.max_score


def test_a_clamp_alone_is_no_clipped_power_curve(ctx):
    """The clipped power curve (mcrt.grade.explain.curves) on a Mitsuba render (seed 67): its values clipped to 1 and
    nothing more give no such candidate (an exponent near 1 is the tone curves' clamp, not an encoding); square-rooted
    and clipped, it is one, with gamma 2."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.curves import curves
    from mcrt.grade.explain.fit import Fit

    X = _mitsuba(67)
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024

    def clipped_power(S):
        fit = Fit(S, R, V, np.ones(R.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
        return next((c for c in curves(fit, Inputs(ctx.explain)) if c.name == "power curve, clipped"), None)

    assert clipped_power(np.minimum(X, 1.0)) is None
    c = clipped_power(np.sqrt(np.minimum(X, 1.0)))
    assert c is not None and c.value == "2-clipped", c and c.value


def test_a_curve_bends_the_noise_of_the_values_it_maps():
    """mcrt.grade.explain.fit.bent_noise: through the identity the noise is the render's; through a square root it is
    about f'(R)^2 times it where the noise is small; through a clamp at 1 it vanishes above 1."""
    from mcrt.grade.explain.fit import bent_noise

    R = np.array([0.04, 0.2, 20.0])
    var = (0.02 * R) ** 2
    assert np.allclose(bent_noise(lambda x: x, R, var), var, rtol=1e-3)
    assert np.allclose(bent_noise(np.sqrt, R, var), var / (4 * R), rtol=0.01)
    assert bent_noise(lambda x: np.minimum(x, 1.0), R, var)[2] == pytest.approx(0.0, abs=1e-12)


def test_the_display_curve_on_the_luminance_is_named(ctx):
    """A Mitsuba render (seed 65) whose pixels' luminance went through the sRGB curve, each colour scaled along to keep
    its hue, saved as floats: claimed as that curve on the luminance; the image loses points."""
    from mcrt.image_files import srgb_oetf

    x = _mitsuba(65)
    lum = (x @ np.array([0.2126, 0.7152, 0.0722]))[..., None]
    res = grade_image("srgb_lum", ctx, [x * np.where(lum > 0, srgb_oetf(lum) / np.maximum(lum, 1e-12), 0.0)],
                      spp=1024)
    fam, said = _claimed(res)
    assert fam == "tone_curve" and res.details["explanation"]["named"] == "tone map srgb on luminance", said
    assert res.score < res.max_score


def test_direct_light_added_twice_is_named(ctx):
    """A Mitsuba path render (seed 62) plus a Mitsuba direct-lighting render with the light hidden (seed 63): the
    direct light counted twice; no other cause."""
    img = _mitsuba(62) + _mitsuba_direct(63)
    res = grade_image("plus_direct", ctx, [img], spp=1024)
    fam, said = _claimed(res)
    assert fam == "direct_twice" and res.details["explanation"]["named"] == "direct light twice", said
    assert named_causes(res)[0] == ["direct_twice"]
    assert res.score < res.max_score


@pytest.fixture(scope="module")
def low_light(tmp_path_factory, grade_cache):
    """The canonical scene with its light 1.5 below the ceiling (the canonical light, 0.01 below it, facing up
    lights only the ceiling right above it: the image is nearly black, as any family times 0 is), and the
    32x32 assignment on it, prepared in the run's cache."""
    from mcrt.scene import CANONICAL

    d = tmp_path_factory.mktemp("low_light")
    text = CANONICAL.read_text(encoding="utf-8").replace("center = [5.0, 0.0, 4.99]", "center = [5.0, 0.0, 3.5]")
    assert "3.5]" in text
    (d / "low.toml").write_text(text, encoding="utf-8")
    a = assignment_from_dict({**ASSIGNMENT, "scene": {**ASSIGNMENT["scene"], "file": str(d / "low.toml")}},
                             str(d / "low32.toml"))
    return a.load_scene(), prepare_context(a, grade_cache)


def test_a_light_facing_the_ceiling_is_named(low_light):
    """The light's normal pointing up, 1.5 below the ceiling (Mitsuba, seed 64): the light facing the other way;
    the same scene rendered correctly (seed 70) claims nothing."""
    s, ctx = low_light
    img = _mitsuba(64, replace(s, light=replace(s.light, normal=(0.0, 0.0, 1.0))))
    res = grade_image("light_up", ctx, [img], spp=1024)
    fam, said = _claimed(res)
    assert fam == "light_facing" and res.details["explanation"]["named"] == "light facing the other way", said
    assert res.score < res.max_score
    res = grade_image("correct", ctx, [_mitsuba(70, s)], spp=1024)
    assert res.score == res.max_score and named_causes(res)[0] == [], res.summary


@pytest.mark.parametrize("name", ["block", "scattered", "unlit", "unlit and one lit"])
def test_black_pixels_are_named_and_lose_points(ctx, name):
    """A Mitsuba render (seed 65) with a 6 x 5 block written as 0, 12 scattered pixels (seed 66), or every pixel
    that Mitsuba's direct integrator (seed 67) finds unlit by the light, the light's own aside (Mitsuba, max depth
    1), alone or with one lit pixel of the floor beside them (a penumbra's pixel whose every sample was stopped):
    the black pixels are claimed, the block by its rows and columns, the unlit ones as the bounced light lost
    where the light is hidden (no other set is, nor the light's own pixels written black), and the image loses
    points."""
    img = _mitsuba(65)
    if name == "block":
        img[10:16, 20:25] = 0.0
    elif name == "scattered":
        flat = img.reshape(-1, 3)
        flat[np.random.default_rng(66).choice(RES * RES, 12, replace=False)] = 0.0
    else:
        seen = _render_spec(Spec("t", None, spp=64), load_scene(), width=RES, height=RES, max_depth=1, seed=67).mean
        unlit = np.all(_mitsuba_direct(67) == 0.0, axis=-1) & np.all(np.asarray(seen) == 0.0, axis=-1)
        if name == "unlit and one lit":
            assert unlit.sum() >= 100 and not unlit[RES - 2, RES // 2]
            unlit[RES - 2, RES // 2] = True  # the floor, lit
        img[unlit] = 0.0
    res = grade_image(name, ctx, [img], spp=1024)
    fam, said = _claimed(res)
    assert fam == "bad_pixels", said
    assert ("where the light is hidden" in said) == name.startswith("unlit"), said
    if name.startswith("unlit"):
        light = _mitsuba(65)
        light[light.max(axis=-1) > 10.0] = 0.0  # the light's own pixels get no light sample either
        said_light = _claimed(grade_image("light_black", ctx, [light], spp=1024))[1]
        assert "where the light is hidden" not in said_light, said_light
        assert named_causes(res)[0] == ["indirect_scale", "roulette"], said
        return
    value = res.details["explanation"]["candidates"][0]["value"]
    assert value["pixels"] == (30 if name == "block" else 12)
    assert value["block"] == ([10, 15, 20, 24] if name == "block" else None)
    assert res.score < res.max_score


@pytest.mark.parametrize("name", ["crosshair", "grid"])
def test_lines_drawn_over_the_render_are_named_where_they_are(ctx, name):
    """A Mitsuba render (seed 63) with the unheralded class's red crosshair through its centre (written blind to the
    grader), or a grey grid drawn every 8 rows and columns: claimed as lines drawn, with their rows and columns,
    and points are lost. The same render 20 times too bright in a display file (whole lines clipped at 1, one value
    too) has no lines drawn."""
    from mcrt.grade.accuracy import unheralded
    from mcrt.grade.explain.pixels import drawn_lines

    img = _mitsuba(63)
    if name == "crosshair":
        drawn, where = unheralded._crosshair(img), f"row {RES // 2} and column {RES // 2}"
    else:
        drawn = img.copy()
        drawn[::8, :] = drawn[:, ::8] = 0.5
        where = "rows 0, 8, 16, 24 and columns 0, 8, 16, 24"
    res = grade_image(name, ctx, [drawn], spp=1024)
    fam, said = _claimed(res)
    assert fam == "bad_pixels" and where in said and named_causes(res)[0] == ["bad_pixels"], said
    assert res.score < res.max_score
    clipped = np.round(np.clip(img * 20.0, 0.0, 1.0) * 255.0) / 255.0
    assert np.all(clipped == 1.0, axis=(1, 2)).any()
    ref = ctx.references["near"]
    assert drawn_lines(clipped, ref.mean, 1.0 / np.maximum(ctx.model_var["near"] / 1024 + ref.var / ref.spp, 1e-30)) == {}


def _mitsuba_aov(aovs: str, seed: int, spp: int = 64) -> np.ndarray:
    """Mitsuba's aov integrator's image (its channels as the AOVs list them)."""
    import mitsuba as mi

    from mcrt.mitsuba_scene import scene_dict

    d = scene_dict(load_scene(), "near", RES, RES, 8, spp=spp)
    d["integrator"] = {"type": "aov", "aovs": aovs}
    return np.asarray(mi.render(mi.load_dict(d), spp=spp, seed=seed), np.float64)


@pytest.mark.parametrize("aovs, words", [
    ("aa:albedo", "the film's albedo buffer"),
    ("nn:sh_normal", "the surface normals written as colours ((n + 1) / 2)"),
    ("dd:depth", "a depth buffer (each pixel the distance to the first surface its rays meet, "),
])
def test_an_auxiliary_buffer_written_for_the_image_is_named(ctx, aovs, words):
    """Mitsuba's aov integrator (seed 64, 64 spp): its albedo buffer, its shading normals as (n + 1) / 2, and its depth
    divided by its largest value in every channel, each handed in for the image: claimed as that buffer (the depth's
    scale within 3 % of 1 / the largest distance), and points are lost."""
    img = _mitsuba_aov(aovs, 64)
    far = float(img.max())
    img = {"aa": img, "nn": (img + 1.0) / 2.0, "dd": np.repeat(img / far, 3, axis=2)}[aovs[:2]]
    res = grade_image(aovs[:2], ctx, [img], spp=64)
    fam, said = _claimed(res)
    assert fam == "wrong_buffer" and words in said and named_causes(res)[0] == ["wrong_buffer"], said
    if aovs == "dd:depth":
        assert res.details["explanation"]["candidates"][0]["value"]["scale"] == pytest.approx(1.0 / far, rel=0.03)
    assert res.score < res.max_score


def test_a_near_black_image_is_no_depth_buffer(ctx):
    """A Mitsuba render (seed 64) written a thousand times too dark (as 12-bit codes read as 16-bit come out, about):
    a depth buffer's two free values would fit it flat, so none is a candidate; the scale is claimed."""
    res = grade_image("dark", ctx, [_mitsuba(64) * 1e-3], spp=1024)
    ex = res.details["explanation"]
    assert not any(c.get("mutant") == "depth buffer" for c in ex["candidates"]), ex["sentence"]
    assert "depth buffer" not in ex["sentence"] and res.score < res.max_score


def test_lamberts_cosine_to_the_eye_is_named(ctx):
    """A Mitsuba render (seed 68) whose light reflected at surfaces of non-zero albedo is times |n . d|, n and d from
    Mitsuba's own shading-normal and position AOVs (seed 69, 256 spp) and the camera's eye, the emission the camera
    sees (Mitsuba, max depth 1) kept: claimed as Lambert's cosine taken to the eye, scored as the BRDF's mistake."""
    aov = _mitsuba_aov("aa:albedo,nn:sh_normal,pp:position", 69, spp=256)
    n, p = aov[..., 3:6], aov[..., 6:9]
    d = p - np.asarray(load_scene().camera("near").eye)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    cos = np.where(aov[..., :3].sum(axis=-1) > 0, np.abs(np.sum(n * d, axis=-1)), 1.0)[..., None]
    full = _mitsuba(68)
    seen = np.asarray(_render_spec(Spec("t", None, spp=1024), load_scene(), width=RES, height=RES, max_depth=1,
                                   seed=68).mean, np.float64)
    res = grade_image("view_cosine", ctx, [seen + cos * (full - seen)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "view_cosine" and named_causes(res)[0] == ["material", "brdf_norm"], said
    assert res.score < res.max_score


@pytest.mark.parametrize("side, forward", [("left", (0.0, 1.0, 0.0)), ("right", (0.0, -1.0, 0.0))])
def test_a_camera_turned_a_quarter_is_named_with_its_side(ctx, side, forward):
    """Mitsuba renders (seed 70) with the near camera looking along +y or -y where the scene says +x (a yaw from atan2
    with its arguments swapped): claimed as the camera turned 90 degrees to that side, and points are lost."""
    s = load_scene()
    s = replace(s, cameras={**s.cameras, "near": replace(s.cameras["near"], forward=forward)})
    res = grade_image(side, ctx, [_mitsuba(70, s)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "rotation" and f"turned 90 degrees to the {side}" in said, said
    assert "camera_rotation" in named_causes(res)[0] and res.score < res.max_score


def test_the_albedo_applied_twice_to_the_first_light_sample_is_named(ctx):
    """A Mitsuba render (seed 71) plus its first hit's direct light (Mitsuba's paths of depth 2 less those of depth 1,
    seed 72) times (rho - 1), rho Mitsuba's albedo AOV (seed 73): the albedo applied twice to the first hit's light
    sample, claimed so, scored as a colour mistake."""
    spec = Spec("t", None, spp=1024)
    d = [np.asarray(_render_spec(spec, load_scene(), width=RES, height=RES, max_depth=k, seed=72).mean, np.float64)
         for k in (1, 2)]
    rho = _mitsuba_aov("aa:albedo", 73, spp=256)
    res = grade_image("albedo_twice", ctx, [_mitsuba(71) + (d[1] - d[0]) * (rho - 1.0)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "direct_albedo" and "albedo applied twice" in said and named_causes(res)[0] == ["albedo"], said
    assert res.score < res.max_score


def test_a_wall_left_out_is_named_as_a_black_surface(ctx):
    """Wall CD left out of the Mitsuba scene (seed 71): in the closed room it is black, which is what a wall of
    albedo 0 looks like; the feedback claims that surface black and names both causes."""
    res = grade_image("no_wall", ctx, [_mitsuba(71, mitsuba_edit=lambda d: {k: v for k, v in d.items()
                                                                          if k != "wall_CD"})], spp=1024)
    fam, said = _claimed(res)
    assert fam == "surface_black" and res.details["explanation"]["named"] == "wall CD black", said
    assert set(named_causes(res)[0]) == {"object_missing", "albedo", "normals"}
    assert "missing from the scene" in said and "normals facing away" in said
    assert res.score < res.max_score


def _object_albedo(name: str, albedo):
    def edit(s):
        return replace(s, objects=tuple(replace(o, material=replace(o.material, albedo=tuple(albedo)))
                                        if o.name == name else o for o in s.objects))
    return edit


def test_a_black_object_is_named_with_every_cause_of_black(ctx):
    """The tetrahedron at albedo 0 (Mitsuba, seed 74): black, as it would be with its normals facing away under
    one-sided shading; the feedback claims it black and names albedo 0 and the normals, not one of them alone nor
    a mirror of reflectance 0 beside it, and not missing (a missing object shows what lies behind it)."""
    res = grade_image("tetra_black", ctx, [_mitsuba(74, _object_albedo("tetrahedron", (0.0, 0.0, 0.0))(load_scene()))],
                      spp=1024)
    fam, said = _claimed(res)
    assert fam == "object_black", said
    assert set(named_causes(res)[0]) == {"albedo", "normals"}, named_causes(res)
    assert "the tetrahedron black" in said and "albedo 0" in said and "normals facing away" in said, said
    assert "missing" not in said and "mirror" not in said, said
    assert res.score < res.max_score


def test_a_render_shifted_by_a_quarter_pixel_is_claimed_as_a_shift(ctx):
    """A Mitsuba render at twice the resolution (seed 75) reduced by keeping every other pixel, img[1::2, 1::2]: the
    image shifted by a quarter pixel right and down, with no blur. The resampling family's reduction from twice the
    resolution by nearest pixels is that image exactly, with one parameter: it is claimed (Occam's rule), a shift
    and a small rotation being the same misregistration read with more parameters."""
    fine = _render_spec(Spec("t", None, spp=1024), load_scene(), width=2 * RES, height=2 * RES, max_depth=8, seed=75)
    img = np.asarray(fine.mean, np.float64)[1::2, 1::2]
    res = grade_image("every_other", ctx, [img], spp=1024)
    fam, said = _claimed(res)
    assert fam == "resampling", said
    value = res.details["explanation"]["candidates"][0]["value"]
    assert value == {"size": [2 * RES, 2 * RES], "method": "nearest", "centre": True}, said
    assert "keeping the nearest pixel" in said and "resampling" in named_causes(res)[0]
    assert res.score < res.max_score


def test_the_light_seen_at_half_its_radiance_is_named_with_its_factor(ctx):
    """A Mitsuba render (seed 76) less half of Mitsuba's render cut at depth 1 (seed 77: the light where the camera
    sees it directly): the light's own pixels at half its radiance, its light on the surfaces right, as an MIS weight
    of 1/2 on emission at the first hit makes it. Named with its factor; the light black (k = 0) is not claimed."""
    img = _mitsuba(76) - 0.5 * _mitsuba(77, max_depth=1)
    res = grade_image("light_seen_half", ctx, [img], spp=1024)
    ex = res.details.get("explanation") or {}
    said = ex.get("sentence", res.summary)
    assert ex.get("family") == "emitter_seen" and ex.get("verdict") in ("claimed", "ambiguous"), said
    assert ex["candidates"][0]["value"] == pytest.approx(0.5, abs=0.03), said
    assert "0.5 times as bright where the camera sees it directly" in said and "light_seen" in named_causes(res)[0]
    assert res.score < res.max_score


def test_a_flipped_render_names_the_orientation(ctx):
    """A Mitsuba render (seed 67) written upside down: the orientation criterion fails, and it is the cause named,
    with the camera's vectors its words name beside the writer's order of rows."""
    res = grade_image("flipped", ctx, [_mitsuba(67)[::-1]], spp=1024)
    assert named_causes(res)[0] == ["orientation", "camera_rotation"], res.summary
    assert res.score < res.max_score


def test_a_correct_render_claims_no_new_family(ctx):
    """A correct Mitsuba render (seed 68): full marks, no cause named."""
    res = grade_image("correct", ctx, [_mitsuba(68)], spp=1024)
    assert res.score == res.max_score and named_causes(res)[0] == [], res.summary


def test_another_mistake_is_not_taken_for_a_new_family(ctx):
    """Wall EF recoloured blue (Mitsuba, seed 69): its albedo, none of the new families (a wall's colour is no
    colour matrix of the whole image)."""
    res = grade_image("wall", ctx, [_mitsuba(69, wall_albedo("EF", (0.15, 0.20, 0.75))(load_scene()))], spp=1024)
    fam, said = _claimed(res)
    assert fam == "albedo", said
    assert not set(named_causes(res)[0]) & set(NEW), named_causes(res)


def _mcrt_clamped(seed: int, clamp: float, spp: int = 1024) -> np.ndarray:
    """mcrt's render with each sample clamped at ``clamp`` (the renderer's sample_clamp trick)."""
    from mcrt.render import render

    s = load_scene()
    settings = s.settings(camera="near", width=RES, height=RES, spp=spp, max_depth=8, light_samples=1)
    return np.asarray(render(s, settings, seed=seed, progress=False, sample_clamp=clamp).mean, np.float64)


def _mitsuba_clamped(seed: int, clamp: float, k: int = 8) -> np.ndarray:
    """Mitsuba's path tracer, one sample in each of k x k sub-pixels, each clamped, then averaged per pixel (a
    student's firefly clamp in a renderer of their own: another estimator than the grader's renders)."""
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    d = scene_dict(load_scene(), "near", RES * k, RES * k, 8, spp=1)
    s = np.minimum(np.asarray(render_with_variance(d, spp=1, seed=seed).mean, np.float64), clamp)
    return s.reshape(RES, k, RES, k, 3).mean(axis=(1, 3))


def test_each_sample_clamped_is_named_with_its_clamp(ctx):
    """mcrt with each sample clamped at 3 (seed 72, 1024 spp; 3 lies between the family's renders at 2 and 4): the
    per-sample clamp is claimed, not a curve on the values (one may be named beside it: at 32 x 32 a clamp this high
    shows mostly on the light), with c recovered to within a quarter octave, and the image loses points."""
    res = grade_image("clamp3", ctx, [_mcrt_clamped(72, 3.0)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "sample_clamp", said
    c = res.details["explanation"]["candidates"][0]["value"]
    assert 3.0 / 2**0.25 <= c <= 3.0 * 2**0.25, c
    assert "each sample clamped at about" in said and "where the scene says 20" in said
    assert named_causes(res)[0][0] == "sample_clamp"  # a curve on the values may be named beside it (rivals)
    assert res.score < res.max_score


def test_the_light_seen_tinted_is_named_with_its_colour(ctx):
    """A Mitsuba render (seed 76) less (0, 0.7, 0.7) times Mitsuba's render cut at depth 1 (seed 77): the light's own
    pixels tinted (1, 0.3, 0.3), its light on the surfaces right, as a debug colour on camera rays that meet the light
    makes it. Named as the light seen with that colour (one factor per channel), not a curve on the values."""
    img = _mitsuba(76) - np.array([0.0, 0.7, 0.7]) * _mitsuba(77, max_depth=1)
    res = grade_image("light_seen_tinted", ctx, [img], spp=1024)
    ex = res.details.get("explanation") or {}
    said = ex.get("sentence", res.summary)
    assert ex.get("family") == "emitter_seen" and ex.get("verdict") in ("claimed", "ambiguous"), said
    assert ex["candidates"][0]["value"] == pytest.approx((1.0, 0.3, 0.3), abs=0.03), said
    assert "tinted there" in said and "light_seen" in named_causes(res)[0]
    assert res.score < res.max_score


def test_a_clamp_in_another_renderer_is_a_sample_clamp_not_a_tone_curve(ctx):
    """Mitsuba, each of 64 samples a pixel clamped at 2 (seed 73; Mitsuba's estimator, not the grader's renders): the
    sample clamp is named, with one parameter, not a curve on the values with one per level (a curve that leaves
    noise too may only be named beside it), and the image loses points. At 32 x 32 and 64 spp the clamp shows on the
    light's own pixels alone, so the light seen directly at a factor (one parameter too) reads the image as well:
    either is claimed, the other named beside it ("so would ..."), never the curve alone."""
    res = grade_image("clamp2", ctx, [_mitsuba_clamped(73, 2.0)], spp=64)
    fam, said = _claimed(res)
    named = named_causes(res)[0]
    assert fam in ("sample_clamp", "emitter_seen") and "sample_clamp" in named, said
    assert set(named) <= {"sample_clamp", "light_seen", "tone_map", "encoding"}, named
    assert res.score < res.max_score


def test_shadow_rays_summed_are_fitted_by_their_count(ctx):
    """30 shadow rays a point summed, not averaged (the course report's count): Mitsuba's light seen directly (cut
    at depth 1) plus 30 times the rest (the full render), one seed (96) so the two share their camera samples. The
    light sample's weight fitted on the grading basis is 30 of its factors, and it leaves the least chi^2 of them
    (the claim is the engine's: at 32 x 32 a monotone curve describes the image as well)."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.fit import Fit
    from mcrt.grade.explain.light_sampling import light_sampling

    d1 = _mitsuba(96, max_depth=1)
    S = d1 + 30.0 * (_mitsuba(96) - d1)
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024
    fit = Fit(S, R, V, np.ones(S.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
    best = light_sampling(fit, Inputs(ctx.explain))[0]
    assert best.value == {"factor": 30.0} and "30 shadow rays a point summed" in best.text, best.text


def test_the_light_sampled_elsewhere_is_named_where_its_samples_are(ctx):
    """A light sampling routine with its own copy of the light, its centre's y typed 1 too small: Mitsuba's light
    seen directly (cut at depth 1, the scene's light) plus the light the moved copy sheds on surfaces (its full render
    minus its own cut at depth 1), one seed (98). The light as sampled is claimed, at the copy's centre, and the
    image loses points."""
    s = load_scene()
    moved = replace(s, light=replace(s.light, center=(s.light.center[0], s.light.center[1] - 1.0, s.light.center[2])))
    S = _mitsuba(98, max_depth=1) + _mitsuba(98, moved) - _mitsuba(98, moved, max_depth=1)
    res = grade_image("sampled_elsewhere", ctx, [S], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "light_sampling" and ex["named"] == "light sampled elsewhere", said
    assert ex["candidates"][0]["value"]["centre"] == pytest.approx(moved.light.center), said
    assert named_causes(res)[0] == ["light_pdf"] and res.score < res.max_score


def test_the_light_sampled_over_a_rectangle_is_named_with_its_edges(ctx):
    """A light sampling routine whose x range starts at the light's centre and is twice its side (x in [5, 9], y on
    the light), the light's pdf 1/A kept: Mitsuba's light seen directly (cut at depth 1, the scene's light) plus half
    the light a 4 x 2 copy over that rectangle sheds on surfaces (its full render minus its own cut at depth 1), one
    seed (104). The rectangle the samples come from is claimed with the light's pdf and its edges, each within one
    cell of the family's grid (a quarter of the light's side: at 32 x 32 a strip that thin on the light's edge is
    within the noise), and the image loses points."""
    s = load_scene()
    over = replace(s, light=replace(s.light, center=(7.0, s.light.center[1], s.light.center[2]),
                                    size=(4.0, s.light.size[1])))
    S = _mitsuba(104, max_depth=1) + 0.5 * (_mitsuba(104, over) - _mitsuba(104, over, max_depth=1))
    res = grade_image("sampled_over", ctx, [S], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "light_sampling" and ex["named"] == "light sampled over a rectangle", said
    v = ex["candidates"][0]["value"]
    assert v["x"] == pytest.approx((5.0, 9.0), abs=0.5) and v["y"] == pytest.approx((-1.0, 1.0), abs=0.5), said
    assert v["pdf"] == "whole light", said
    assert named_causes(res)[0] == ["light_pdf"] and res.score < res.max_score


def test_where_the_light_is_sampled_is_said_where_its_samples_lead(ctx):
    """The rule on its own (mcrt.grade.broader.reading): the light sampled elsewhere leading a partial reading says
    where the light's samples are drawn, which names the light's sampling, where what is left lies on the room's
    surfaces; left on the light's own pixels too, which no light sample changes, nothing broader is said; a light
    sample's weight alone (a factor a BRDF or an emitter can hold) says nothing broader either."""
    from mcrt.grade.accuracy.run import CAUSE_OF
    from mcrt.grade.broader import reading
    from mcrt.grade.candidates import Candidate

    R = _mitsuba(72)
    labels, names = ctx.labels["near"], ctx.label_names
    var = ctx.model_var["near"].astype(np.float64) / 1024
    mask = np.ones(R.shape[:2], bool)
    floor, light = names.index("the floor"), names.index("the light")
    rest = np.zeros_like(R)
    for name in ("light sampled elsewhere", "light sampled over a rectangle", "light sampled on a quarter"):
        lead = Candidate("light_sampling", name, "the light's samples drawn elsewhere", 0.0, 4, change=rest)
        assert reading(lead, rest, R, mask, var, labels, names, [floor, light]) is None
        fam, words = reading(lead, rest, R, mask, var, labels, names, [floor])
        assert fam == "light_region" and "where the light's samples are drawn" in words
        assert CAUSE_OF[fam] == ("light_pdf",)
    weight = Candidate("light_sampling", "light sample's weight", "the light reaching surfaces 2 times", 0.0, 0,
                       change=rest)
    assert reading(weight, rest, R, mask, var, labels, names, [floor]) is None


def test_several_surfaces_colours_are_named_together(ctx):
    """A Mitsuba render (seed 99) with every diffuse albedo's channels clamped at 0.6 (a guard against reflecting
    more than came in, set too low): five walls, the ceiling and the tetrahedron change, no single surface explains
    it, and no fixed remapping is a clamp. Several surfaces' colours are claimed together (of those in view at
    32 x 32, wall CD and the ceiling among them), each within 0.05 of its clamped colour in every channel, and the
    image loses points."""
    s = load_scene()

    def c(v):
        return tuple(min(float(x), 0.6) for x in v)

    room = replace(s.room, floor_albedo=c(s.room.floor_albedo), ceiling_albedo=c(s.room.ceiling_albedo),
                   walls=tuple(replace(w, albedo=c(w.albedo)) for w in s.room.walls))
    objects = tuple(replace(o, material=replace(o.material, albedo=c(o.material.albedo)))
                    if hasattr(o.material, "albedo") else o for o in s.objects)
    clamped = replace(s, room=room, objects=objects)
    res = grade_image("clamped", ctx, [_mitsuba(99, clamped)], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "albedo" and ex["named"] == "albedos of several surfaces", said
    truth = {f"wall {''.join(w.corners)}": w.albedo for w in room.walls} | {"the ceiling": room.ceiling_albedo}
    fitted = ex["candidates"][0]["value"]
    assert {"wall CD", "the ceiling"} <= set(fitted), said
    for label, v in fitted.items():
        if label in truth:
            assert np.allclose(v, truth[label], atol=0.05), (label, v, truth[label])
    assert named_causes(res)[0] == ["albedo"] and res.score < res.max_score


def test_a_filter_written_with_np_roll_is_named_with_its_wrapped_border(ctx):
    """A Mitsuba render (seed 101) filtered by the 3 x 3 binomial kernel written as a weighted mean of np.roll's
    shifted copies: the border wraps round to the opposite edge. The filter is claimed, in words that say so."""
    x = _mitsuba(101)
    w = {-1: 1.0, 0: 2.0, 1: 1.0}
    S = sum(w[dy] * w[dx] * np.roll(x, (dy, dx), axis=(0, 1)) for dy in w for dx in w) / 16.0
    res = grade_image("rolled", ctx, [S], spp=1024)
    fam, said = _claimed(res)
    assert fam == "blur" and "binomial" in said and "wrapped round to the opposite edge" in said, said
    assert "sum to" not in said and res.score < res.max_score


def test_the_light_sample_times_pi_is_fitted_by_its_factor(ctx):
    """The light's radiance multiplied by pi in the light sample only (an exitance's factor): Mitsuba's light seen
    directly (cut at depth 1) plus pi times the rest, one seed (102). The light sample's weight fitted on the grading
    basis is pi of its factors (the claim is the engine's: at 32 x 32 a monotone curve describes the image as well)."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.fit import Fit
    from mcrt.grade.explain.light_sampling import light_sampling

    d1 = _mitsuba(102, max_depth=1)
    S = d1 + np.pi * (_mitsuba(102) - d1)
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024
    fit = Fit(S, R, V, np.ones(S.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
    best = light_sampling(fit, Inputs(ctx.explain))[0]
    assert best.value == {"factor": pytest.approx(np.pi)} and "divided by pi" not in best.text, best.text
    assert "multiplied by pi in the light sample" in best.text, best.text


def test_a_light_with_one_side_doubled_is_named_with_its_sides(ctx):
    """A Mitsuba render (seed 103) of the scene with the light's side along y doubled and x kept (a half-width
    forgotten in y alone): the light's size is claimed as 2 x 4."""
    s = load_scene()
    wide = replace(s, light=replace(s.light, size=(s.light.size[0], 2.0 * s.light.size[1])))
    res = grade_image("one_side", ctx, [_mitsuba(103, wide)], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "light_size" and ex["candidates"][0]["value"] == pytest.approx(wide.light.size), said


def test_the_variance_buffer_written_for_the_mean_is_fitted(ctx):
    """Mitsuba's per-sample variance (its render's variance buffer, seed 104) written where the mean belongs: of the
    film's buffers the variance fits better than the squares, with k near 1 (the buffer as written, divided by no
    other count), and leaves less chi^2 than no change."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.buffers import wrong_buffer
    from mcrt.grade.explain.fit import Fit
    from mcrt.mitsuba_scene import render_with_variance, scene_dict

    d = scene_dict(load_scene(), "near", RES, RES, 8, spp=1024)
    S = np.maximum(np.asarray(render_with_variance(d, spp=1024, seed=104).variance, np.float64), 0.0)
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024
    fit = Fit(S, R, V, np.ones(S.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
    best = min(wrong_buffer(fit, Inputs(ctx.explain)), key=lambda c: c.chi2)
    assert best.value["buffer"] == "variance" and 0.5 < best.value["scale"] < 2.0, best.value
    assert best.chi2 < fit.chi0 and "variance buffer written for its mean" in best.text


def test_colours_a_few_hundredths_off_are_no_colours_typed_wrong(ctx):
    """Walls CD and DE at 0.95 times their colours (Mitsuba, seed 105): every channel within 0.04 of the scene's,
    what a change of the light makes on several surfaces too. Several surfaces' colours are no candidate (a colour
    typed, read or clamped wrongly moves by a tenth); at 0.8 times (seed 106) they are, with both walls changed.
    The surfaces fitted are those in view, as the engine passes them (the grading context's labels)."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.fit import Fit
    from mcrt.grade.explain.scene import albedos

    s = load_scene()
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024
    for k, seed, found in ((0.95, 105, False), (0.8, 106, True)):
        walls = tuple(replace(w, albedo=tuple(k * a for a in w.albedo)) if "".join(w.corners) in ("CD", "DE") else w
                      for w in s.room.walls)
        S = _mitsuba(seed, replace(s, room=replace(s.room, walls=walls)))
        fit = Fit(S, R, V, np.ones(S.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
        got = albedos(fit, Inputs(ctx.explain, labels=ctx.labels["near"], label_names=ctx.label_names))
        assert bool(got) == found, (k, [c.value for c in got])
        if found:
            assert {"wall CD", "wall DE"} <= set(got[0].value), got[0].value


def test_a_diffuse_bounce_left_in_the_local_frame_is_named(ctx):
    """The bounce at the first surface a camera ray meets drawn about +z, never turned to the normal: Mitsuba's light
    sample there and Mitsuba's path from the mistaken direction on (unguessed's maker, tuned half, 512 spp, seed 5).
    Claimed as that bounce at the first hit, the cause the indirect light's, and the image loses points."""
    from mcrt.grade.accuracy.unguessed import _bounce_in_local_frame

    S = _bounce_in_local_frame(np.zeros((RES, RES, 3)), spp=512, seed=5)
    res = grade_image("local_frame", ctx, [S], spp=512)
    fam, said = _claimed(res)
    assert fam == "bounce", said
    assert res.details["explanation"]["candidates"][0]["value"] == {"bounce": "local_frame", "at": "first"}, said
    assert named_causes(res)[0] == ["indirect_scale"] and res.score < res.max_score


def test_a_bounce_times_its_pdf_is_named(ctx):
    """The bounce at the first surface a camera ray meets weighted by f cos pdf for f cos / pdf (albedo cos^2 / pi^2
    a bounce): unvisited's maker (tuned half, 512 spp, seed 9), Mitsuba's light sample there and its path after the
    bounce. The bounce at the first hit fits it all (a roulette that never divides, which also leaves the indirect
    light nearly gone, may tie), its words are in the feedback, and the image loses points."""
    from functools import partial

    from mcrt.grade.accuracy import unprompted, unvisited

    S = partial(unprompted._first_bounce, spp=512, seed=9, draw=unvisited._times_pdf)(np.zeros((RES, RES, 3)))
    res = grade_image("times_pdf", ctx, [S], spp=512)
    ex = res.details["explanation"]
    bounce = next(c for c in ex["candidates"] if c["family"] == "bounce")
    assert bounce["value"] == {"bounce": "times_pdf", "at": "first"} and bounce["explained"] > 0.95, bounce
    assert ex["verdict"] == "claimed" and "multiplied by the pdf" in ex["sentence"], ex["sentence"]
    assert "indirect_scale" in named_causes(res)[0] and res.score < res.max_score


def test_paths_ended_at_their_first_diffuse_surface_are_named_beside_the_bounce_times_its_pdf(ctx):
    """A throughput kept in an integer array (0 after a diffuse bounce, 1 through the mirror): unattested's maker
    (held out there, in view since; 512 spp, seed 10 here), Mitsuba's samples of depth 2 from the first diffuse
    surface. The bounce times its pdf leaves the same image (its light after a bounce is a few per cent), so its
    words name both: where it is claimed the path's depth is among the causes, and here, where a depth cut ties,
    nothing is claimed. The image loses points."""
    from mcrt.grade.accuracy import unattested

    S = unattested._ended_at_first_diffuse(np.zeros((RES, RES, 3)), spp=512, seed=10)
    res = grade_image("int_throughput", ctx, [S], spp=512)
    ex = res.details["explanation"]
    assert "paths that end at the first diffuse surface they meet" in ex["sentence"], ex["sentence"]
    assert ex["verdict"] in ("claimed", "ambiguous") and res.score < res.max_score, ex["sentence"]
    if ex["verdict"] == "claimed":
        assert "depth" in named_causes(res)[0], ex["sentence"]


def test_a_bounce_weighted_by_the_albedos_mean_is_named(ctx):
    """The bounce at the first surface a camera ray meets weighted by the mean of the albedo's channels for the
    albedo: unremarked's maker (tuned half, 512 spp, seed 11; Mitsuba's light sample and path after the bounce).
    The best fit is that bounce at the first hit, its words in the feedback, and the image loses points."""
    from mcrt.grade.accuracy import unremarked

    res = grade_image("albedo_mean", ctx, [unremarked._albedo_mean(np.zeros((RES, RES, 3)), spp=512, seed=11)],
                      spp=512)
    ex = res.details["explanation"]
    best = ex["candidates"][0]
    assert best["family"] == "bounce" and best["value"] == {"bounce": "albedo_mean", "at": "first"}, ex["sentence"]
    assert "mean of the albedo's channels" in ex["sentence"] and res.score < res.max_score
    assert "indirect_scale" in named_causes(res)[0]


def test_the_first_hits_light_samples_averaged_over_the_batch_are_named(ctx):
    """The light samples at the first surface a camera ray meets averaged over the whole batch and broadcast back (a
    mean over the wrong axis): unremarked's maker (tuned half, 512 spp, seed 12; Mitsuba's own light samples, its path
    after them). Claimed as one colour of direct light on every surface, the cause a light sample's, and the image
    loses points. With no light sample there at all, no batch's mean is read (that is the direct light missing)."""
    from mcrt.grade.accuracy import unheralded, unremarked

    S = unheralded._first_vertex(np.zeros((RES, RES, 3)), spp=512, seed=12, direct=unremarked._batch_mean_light)
    res = grade_image("batch_mean", ctx, [S], spp=512)
    fam, said = _claimed(res)
    assert fam == "direct_mean" and "one and the same colour" in said, said
    assert "light_pdf" in named_causes(res)[0] and res.score < res.max_score
    # No light sample there at all (seed 13): a mean of nothing is the direct light missing, not read as a batch's.
    S = unheralded._first_vertex(np.zeros((RES, RES, 3)), spp=512, seed=13,
                                 direct=lambda mscene, rng, p, n, rho, mitsuba: np.zeros(np.shape(mitsuba)))
    res = grade_image("unlit", ctx, [S], spp=512)
    ex = res.details["explanation"]
    assert "direct_mean" not in [c["family"] for c in ex["candidates"]], ex["sentence"]


def test_a_half_circle_azimuth_is_read_in_its_frame(ctx):
    """The bounce at the first surface a camera ray meets with the azimuth pi u, in a frame built from (1, 0, 0)
    (unforeseen's maker, tuned half, 512 spp, seed 6): the best fit is that bounce in that frame, not in the two
    others, whose halves differ. (At 32 x 32 and the basis's 256 spp, 'at the first hit' and 'at every hit' differ
    by less than the basis's noise; the 64 x 64 assignment tells them apart, reports/grading_accuracy.)"""
    from mcrt.grade.accuracy.unforeseen import _bounce_half_circle

    S = _bounce_half_circle(np.zeros((RES, RES, 3)), spp=512, seed=6)
    res = grade_image("half_circle", ctx, [S], spp=512)
    best = res.details["explanation"]["candidates"][0]
    assert best["family"] == "bounce" and best["value"]["bounce"] == "half_azimuth_axis", best
    assert res.score < res.max_score


def test_a_bounce_on_the_whole_sphere_at_every_hit_is_named(ctx):
    """Every diffuse bounce uniform on the sphere with the hemisphere's pdf (each bounce half its weight, the light
    samples right), made from Mitsuba by the physics: twice its render with every albedo halved, less its render with
    every albedo 0 (seeds 101, 102). Its words name that bounce at every hit, the cause the indirect light's (a
    path's weight halved from the first hit on differs from it only where a path goes on from the mirror, which
    32 x 32 pixels do not tell apart: either may lead), and the image loses points."""
    from test_tricks import _albedos_scaled

    s = load_scene()
    S = 2.0 * _mitsuba(101, _albedos_scaled(s, 0.5)) - _mitsuba(102, _albedos_scaled(s, 0.0))
    res = grade_image("whole_sphere", ctx, [S], spp=200)  # its noise: 4 times a halved render's, plus one
    fam, said = _claimed(res)
    causes = named_causes(res)[0]
    assert fam in ("bounce", "path_weight") and "indirect_scale" in causes, said
    assert set(causes) <= {"indirect_scale", "roulette"}, causes  # a path weight's words name roulette's divisor too
    assert "drawn uniformly on the whole sphere but weighted with the hemisphere's pdf" in said, said
    assert "at every diffuse surface a path meets" in said and res.score < res.max_score


def _walls(scene, colours):
    """``scene`` with its walls, in the room's order, of the albedos ``colours``."""
    walls = tuple(replace(w, albedo=tuple(c)) for w, c in zip(scene.room.walls, colours))
    return replace(scene, room=replace(scene.room, walls=walls))


def test_every_wall_of_one_colour_is_named_with_whose_colour(ctx):
    """A Mitsuba render (seed 103) with all six walls given wall CD's yellow (a loop that reads one wall's colour):
    claimed as every wall of one colour, fitted within 0.05 of CD's in each channel and named as CD's; no single
    surface and no sum of surfaces' changes fits it (the walls light one another)."""
    s = load_scene()
    cd = next(w.albedo for w in s.room.walls if "".join(w.corners) == "CD")
    res = grade_image("walls_cd", ctx, [_mitsuba(103, _walls(s, [cd] * len(s.room.walls)))], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "albedo" and ex["named"] == "every wall one colour" and "wall CD's colour" in said, said
    assert np.abs(np.asarray(ex["candidates"][0]["value"]) - cd).max() <= 0.05, said
    assert named_causes(res)[0] == ["albedo"] and res.score < res.max_score


def test_every_wall_black_names_every_cause_of_black(ctx):
    """A Mitsuba render (seed 108) with all six walls of albedo 0: every wall black, as it would be with every wall
    missing from the closed room or facing away under one-sided shading. Where the reading is every wall of one
    colour, it says black and names every cause of that, not a colour alone."""
    s = load_scene()
    res = grade_image("walls_black", ctx, [_mitsuba(108, _walls(s, [(0.0, 0.0, 0.0)] * len(s.room.walls)))], spp=1024)
    ex = res.details["explanation"]
    named = named_causes(res)[0]
    assert "object_missing" in named and "normals" in named, ex["sentence"]
    if ex["named"] == "every wall one colour":
        assert ex["family"] == "surface_black" and "every wall black" in ex["sentence"], ex["sentence"]
    assert res.score < res.max_score


def test_the_walls_colours_two_places_off_are_named_with_their_step(ctx):
    """A Mitsuba render (seed 104) with each wall given the colour of the wall two places after it in the room's
    order (an index off by two): claimed as the walls' colours two places off, not one place. (Its colours make the
    mirrored view the closer in luminance and colour; the orientation check must not take it for a mirrored image.)"""
    s = load_scene()
    cs = [w.albedo for w in s.room.walls]
    res = grade_image("walls_plus2", ctx, [_mitsuba(104, _walls(s, cs[2:] + cs[:2]))], spp=1024)
    fam, said = _claimed(res)
    assert fam == "albedo_swap" and res.details["explanation"]["candidates"][0]["value"] == {"walls": "after",
                                                                                             "k": 2}, said
    assert "2 places after it" in said and res.score < res.max_score


def test_an_image_shifted_by_half_a_pixel_after_rendering_is_named_as_a_shift(ctx):
    """A Mitsuba render (seed 105) shifted half a pixel left by scipy.ndimage.shift with order 1 (moved and blurred):
    claimed as the image shifted after rendering, by (-0.5, 0) with interpolation; the cause a pixel offset."""
    from scipy.ndimage import shift

    S = shift(_mitsuba(105), (0.0, -0.5, 0.0), order=1, mode="nearest")
    res = grade_image("shifted_left", ctx, [S], spp=1024)
    fam, said = _claimed(res)
    ex = res.details["explanation"]
    assert fam == "pixel_offset" and ex["named"] == "image shifted after rendering", said
    assert ex["candidates"][0]["value"] == {"dx": -0.5, "dy": 0.0, "method": "bilinear", "edge": "nearest"}, said
    assert "pixel_offset" in named_causes(res)[0] and res.score < res.max_score


def test_the_light_of_the_last_vertex_alone_is_named_as_a_depth_mistake(ctx):
    """The radiance assigned at each vertex, not added: Mitsuba's light seen directly (max depth 1, seed 106) plus
    its paths of exactly 8 segments (max depth 8 minus max depth 7, seed 107, one seed for both). Its words name the
    last vertex's light kept (beside any other reading that fits as well), and the image loses points."""
    S = _mitsuba(106, max_depth=1) + _mitsuba(107) - _mitsuba(107, max_depth=7)
    res = grade_image("last_vertex", ctx, [S], spp=1024)
    said = _claimed(res)[1]
    assert "the radiance assigned, not added, at each vertex" in said, said
    assert "depth" in named_causes(res)[0] and res.score < res.max_score


def test_a_mirror_handled_for_camera_rays_only_is_named(ctx):
    """The mirror right for the camera's rays and black to every other ray, made from Mitsuba at 4 x 4 sub-pixels
    (seed 108): where a sub-pixel's centre ray meets the sphere (NumPy's ray-sphere test), the scene's render,
    elsewhere the render with the sphere's reflectance 0 (one seed), box-filtered to the grade's pixels. The mirror's
    family reads it as the mirror handled for camera rays only, explaining at least 90 % of the difference, and the
    image loses points. (At 32 x 32 and the basis's 256 spp a path's weight off at the second hit fits as closely;
    which is claimed is the 64 x 64 assignment's to tell, reports/grading_accuracy.)"""
    from test_tricks import _sphere_seen

    from mcrt.scene import Mirror

    s, k = load_scene(), 4
    black = replace(s, objects=tuple(replace(o, material=Mirror(reflectance=(0.0, 0.0, 0.0)))
                                     if isinstance(o.material, Mirror) else o for o in s.objects))
    fine = [np.asarray(_render_spec(Spec("t", None, spp=256), sc, width=k * RES, height=k * RES, max_depth=8,
                                    seed=108).mean, np.float64) for sc in (s, black)]
    seen = _sphere_seen(s, k * RES, points=((0.5, 0.5),), dilate=0)
    S = np.where(seen, fine[0], fine[1]).reshape(RES, k, RES, k, 3).mean(axis=(1, 3))
    res = grade_image("camera_only", ctx, [S], spp=4096)
    mine = [c for c in res.details["explanation"]["candidates"] if c["mutant"] == "mirror computed wrongly"]
    assert mine and mine[0]["value"] == {"mirror": "camera_only", "at": "every"} and mine[0]["explained"] >= 0.9, mine
    assert "the mirror handled for camera rays only" in mine[0]["description"] and res.score < res.max_score


def test_a_box_filter_of_two_pixels_is_named_beside_the_half_pixel_shift_it_equals(ctx):
    """A Mitsuba render (seed 109) through scipy.ndimage.uniform_filter with a size of (2, 2, 1): each pixel the
    mean of a 2 x 2 block, which is the image shifted by half a pixel with bilinear interpolation. The words name both
    (a filter, and the shift), and the image loses points."""
    from scipy.ndimage import uniform_filter

    res = grade_image("box2", ctx, [uniform_filter(_mitsuba(109), size=(2, 2, 1))], spp=1024)
    said = _claimed(res)[1]
    assert "a box filter of 2 x 2 pixels" in said, said
    assert {"blur", "pixel_offset"} <= set(named_causes(res)[0]) and res.score < res.max_score


def test_the_direct_light_missing_on_one_object_is_named_on_it(ctx):
    """Mitsuba's render (seed 110) less its direct light (max depth 2 minus max depth 1, same seed) on the
    tetrahedron's pixels (the context's surface labels): the tetrahedron shaded by a branch that never samples the
    light. The words name the direct light missing on the tetrahedron (claimed, or as one reading of two), and the
    image loses points."""
    full, d2, d1 = _mitsuba(110), _mitsuba(110, max_depth=2), _mitsuba(110, max_depth=1)
    labels = ctx.labels["near"]
    tetra = labels == next(i for i, n in enumerate(ctx.label_names) if n.startswith("the tetrahedron"))
    S = full - np.where(tetra[..., None], d2 - d1, 0.0)
    res = grade_image("tetra_no_direct", ctx, [S], spp=1024)
    said = _claimed(res)[1]
    assert "lit as by light that has bounced alone: the direct light missing on it" in said, said
    assert res.score < res.max_score


def _tuned(module, name: str):
    """Case ``name`` of class ``module``'s tuned half, a Mitsuba render at RES x RES with its own spp and seed."""
    from accuracy_helpers import build, by_name

    spec = by_name(module.SPECS, name)
    assert not spec.held_out
    return build(spec, RES)


def test_an_objects_geometry_is_said_where_its_size_explains_most(ctx):
    """The tetrahedron's faces parallelograms (its triangle test u <= 1 and v <= 1 for u + v <= 1): unheard's maker
    (tuned half; a Mitsuba render). No size or shift of the tetrahedron leaves noise, but its size explains most of
    the difference: the reading stays partial and says the tetrahedron's geometry, which names its shape; the points
    are those of the partial reading."""
    from mcrt.grade.accuracy import unheard

    c = _tuned(unheard, "tetra_parallelogram_faces")
    res = grade_image("parallelograms", ctx, [c.image], spp=c.spp)
    ex = res.details["explanation"]
    assert ex["verdict"] == "partial" and ex["broader"] == "object_geometry", ex["sentence"]
    assert "the tetrahedron's geometry" in ex["sentence"] and "object_shape" in named_causes(res)[0]
    assert res.score < res.max_score


@pytest.mark.parametrize("module, name", [("unmet", "floor_fan_short"), ("unheard", "wall_quads_half")])
def test_black_pixels_with_the_room_darker_are_faces_missing(ctx, module, name):
    """Faces of the room missing (the floor's fan one triangle short; each wall's quad its first triangle only): the
    classes' makers (tuned half; Mitsuba renders of the void behind). The black pixels explain most of the difference;
    the rest of the room is darker, the light escaping: the words say faces missing, which names a mesh's faces."""
    from importlib import import_module

    c = _tuned(import_module(f"mcrt.grade.accuracy.{module}"), name)
    res = grade_image(name, ctx, [c.image], spp=c.spp)
    ex = res.details["explanation"]
    assert ex["verdict"] == "partial" and ex["broader"] == "room_faces", ex["sentence"]
    assert "faces missing from the room" in ex["sentence"] and "mesh_face" in named_causes(res)[0]


@pytest.mark.parametrize("walls, seed", [(("wall_CD", "wall_EF"), 73), (("wall_BC", "wall_CD"), 75)])
def test_walls_missing_are_no_colours_and_point_to_faces(ctx, walls, seed):
    """Two walls left out of the scene: Mitsuba renders of the room with the void behind them. A black wall reflects
    as little as a missing one, so darker colours of several surfaces come close in chi^2; but the hand-in is 0 where
    the light reaches those walls, which no colour of theirs but black makes: the words name them black, missing
    among the causes, or point to faces missing from the room, and name no colour alone. The image loses points."""
    from mcrt.grade.accuracy import fresh
    from mcrt.grade.accuracy.run import is_named

    def edit(d):
        for name in walls:
            d = fresh._without_mesh(d, name)
        return d

    res = grade_image("walls_missing", ctx, [_mitsuba(seed, mitsuba_edit=edit)], spp=1024)
    ex = res.details["explanation"]
    named = named_causes(res)[0]
    assert is_named("mesh_face", named) and ("albedo" not in named or "object_missing" in named), ex["sentence"]
    assert res.score < res.max_score


def test_a_change_that_lights_black_pixels_is_not_adequate(ctx):
    """The rules on their own (mcrt.grade.explain.pixels.black_holes, mcrt.grade.adequacy.holes_left), on a Mitsuba
    render (seed 74) as the reference: a patch of the floor 0 in the hand-in is a hole; a change that keeps 5 % of the floor's light there
    leaves it (at the reference's noise of 1024 spp), one that keeps 1 % does not, nor one that keeps 5 % with noise
    ten times the reference's there; the same patch in a shadow-only image (no pixel lit) is no hole, nor is a
    patch under the least share of pixels, nor are the same pixels scattered (every other one), nor the patch in an
    image a tenth as bright around it; three rows in four black (workers that each render the same rows) are holes,
    lines of them."""
    from mcrt.grade.adequacy import HOLE_LIT, holes_left
    from mcrt.grade.explain.pixels import MIN_HOLES, black_holes

    R = _mitsuba(74)
    labels, names = ctx.labels["near"], ctx.label_names
    floor = labels == names.index("the floor")
    r, c = (int(np.median(x)) for x in np.nonzero(floor))
    patch = np.zeros_like(floor)
    patch[r - 3:r + 4, c - 3:c + 4] = True  # a 7 x 7 patch in the floor's middle
    assert floor[patch].all() and MIN_HOLES * patch.size <= patch.sum() < floor.sum()
    S = np.where(patch[..., None], 0.0, R)
    mask, lit = np.ones(R.shape[:2], bool), np.ones(R.shape[:2], bool)
    holes = black_holes(S, R, mask, lit)
    assert holes is not None and np.array_equal(holes, patch)
    var = ctx.model_var["near"].astype(np.float64) / 1024
    for keep, noise, left in ((0.05, 1, True), (0.01, 1, False), (0.05, 100, False)):
        change = np.where(patch[..., None], (keep - 1.0) * R, 0.0)
        assert (holes_left(R, change, holes, noise * var, labels) is not None) == left
    assert HOLE_LIT == 0.02
    assert black_holes(S, R, mask, ~lit) is None
    few = patch & (np.cumsum(patch.ravel()).reshape(patch.shape) <= int(MIN_HOLES * patch.size) - 1)
    assert black_holes(np.where(few[..., None], 0.0, R), R, mask, lit) is None
    yy, xx = np.indices(patch.shape)
    scattered = floor & ((yy + xx) % 2 == 0)
    assert scattered.sum() >= patch.sum() and black_holes(np.where(scattered[..., None], 0.0, R), R, mask, lit) is None
    assert black_holes(np.where(patch[..., None], 0.0, 0.1 * R), R, mask, lit) is None
    rows = yy % 4 != 0
    found = black_holes(np.where(rows[..., None], 0.0, R), R, mask, lit)
    assert found is not None and found.sum() >= 0.9 * rows.sum()


def test_black_pixels_are_faces_only_with_the_room_darker_and_not_the_brightest(ctx):
    """The rule on its own (mcrt.grade.broader.room_faces), on a Mitsuba render (seed 71) as the reference: black
    pixels on the floor with the rest 4 % darker are faces missing (k = 0.04); with it 4 % brighter, or 0.2 %
    darker, they are not; nor are the reference's brightest pixels black with the rest darker (codes overflowing)."""
    from mcrt.grade.broader import room_faces
    from mcrt.grade.candidates import Candidate

    R = _mitsuba(71)
    labels, names = ctx.labels["near"], ctx.label_names
    var = ctx.model_var["near"].astype(np.float64) / 1024
    mask = np.ones(R.shape[:2], bool)

    def lead(bad):
        return Candidate("bad_pixels", "black pixels", "pixels black where the scene is not", 0.0, 1,
                         value={"pixels": int(bad.sum()), "in_shadow": False}, change=np.where(bad[..., None], -R, 0.0))

    floor = labels == names.index("the floor")
    patch = floor & (np.cumsum(floor, axis=1) <= 3)  # a few pixels of the floor in each of its rows
    assert 10 <= patch.sum() < floor.sum()
    rest = np.where(patch[..., None], 0.0, 1.0)
    assert room_faces(lead(patch), -0.04 * R * rest, R, mask, var, labels, names) == pytest.approx(0.04, rel=1e-6)
    assert room_faces(lead(patch), 0.04 * R * rest, R, mask, var, labels, names) is None
    assert room_faces(lead(patch), -0.002 * R * rest, R, mask, var, labels, names) is None
    lum = R @ np.array([0.2126, 0.7152, 0.0722])
    bright = (lum > np.quantile(lum, 0.8)) & (lum < 1.0) & ~(labels == names.index("the light"))
    rest = np.where(bright[..., None], 0.0, 1.0)
    assert room_faces(lead(bright), -0.04 * R * rest, R, mask, var, labels, names) is None


def test_light_moved_between_surfaces_is_no_colours_typed_wrong(ctx):
    """The cosine-weighted bounce's disk sample drawn in the square (its rejection left out) at the first surface a
    camera ray meets: unlooked's maker (tuned half; Mitsuba's light sample and path after it). It darkens the ceiling
    and moves a few hundredths of light between other surfaces, up on some and down on others: no colours of several
    surfaces are claimed for it (nor any colour)."""
    from mcrt.grade.accuracy import unlooked

    c = _tuned(unlooked, "bounce_disk_in_square")
    res = grade_image("disk_in_square", ctx, [c.image], spp=c.spp)
    ex = res.details["explanation"]
    assert "albedo" not in named_causes(res)[0], ex["sentence"]
    assert not any(x["mutant"] == "albedos of several surfaces" for x in ex["candidates"]), ex["sentence"]
    assert res.score < res.max_score


def test_an_objects_geometry_is_not_said_from_its_own_pixels_alone(ctx):
    """The rule on its own (mcrt.grade.broader.reading): the sphere's size leading a partial reading says the
    sphere's geometry only where what is left lies beside it too (a wall); left on the mirror sphere alone, it could
    as well be the mirror's reflections (its material), and its geometry is not said."""
    from mcrt.grade.broader import reading
    from mcrt.grade.candidates import Candidate

    R = _mitsuba(72)
    labels, names = ctx.labels["near"], ctx.label_names
    var = ctx.model_var["near"].astype(np.float64) / 1024
    mask = np.ones(R.shape[:2], bool)
    lead = Candidate("object_size", "size of the sphere", "the sphere's radius 0.98 times the scene's", 0.0, 1,
                     value={"object": "sphere", "scale": 0.98}, change=np.zeros_like(R))
    sphere, wall = names.index("the mirror sphere"), next(k for k, n in enumerate(names) if n.startswith("wall DE"))
    rest = np.zeros_like(R)
    assert reading(lead, rest, R, mask, var, labels, names, [sphere]) is None
    fam, words = reading(lead, rest, R, mask, var, labels, names, [sphere, wall])
    assert fam == "object_geometry" and "the sphere's geometry" in words


def test_one_objects_own_pixels_are_said_as_how_it_looks(ctx):
    """The rule on its own (mcrt.grade.broader.surface_object), on a Mitsuba render (seed 72): a lead that changes
    the tetrahedron's (or the mirror sphere's) pixels, with what is left on that object alone, says how the object
    itself looks (its material, normals or faces; for the mirror, the directions it reflects), naming no one of them;
    with what is left beside it too, or a lead that changes another surface most, nothing is said."""
    from mcrt.grade.broader import reading
    from mcrt.grade.candidates import Candidate

    R = _mitsuba(72)
    labels, names = ctx.labels["near"], ctx.label_names
    var = ctx.model_var["near"].astype(np.float64) / 1024
    mask = np.ones(R.shape[:2], bool)
    tetra = next(k for k, n in enumerate(names) if n.startswith("the tetrahedron"))
    sphere, floor = names.index("the mirror sphere"), names.index("the floor")

    def lead(*on, k=0.1):
        where = np.isin(labels, on)[..., None]
        return Candidate("scene", "albedo", "the surface's albedo", 0.0, 3, change=np.where(where, -k * R, 0.0))

    rest = np.zeros_like(R)
    fam, words = reading(lead(tetra), rest, R, mask, var, labels, names, [tetra])
    assert fam == "object_surface" and "how the tetrahedron itself looks" in words and "its normals" in words
    fam, words = reading(lead(sphere), rest, R, mask, var, labels, names, [sphere])
    assert fam == "sphere_surface" and "what the mirror sphere shows" in words and "after the mirror bounce" in words
    assert reading(lead(tetra), rest, R, mask, var, labels, names, [tetra, floor]) is None
    assert reading(lead(floor), rest, R, mask, var, labels, names, [tetra]) is None


def test_a_bounce_drawn_otherwise_is_said_where_a_bounce_mistake_explains_most(ctx):
    """Two mistakes on a Mitsuba render (seed 74): the bounce's disk radius u for sqrt(u) at every diffuse hit (mcrt's
    render of it, the explanation basis's) and the floor 5 % brighter. The bounce mistake explains most of the
    difference and leaves the floor: the reading stays partial and says the diffuse bounce, which names the light
    that bounces and, beside the bounce, Russian roulette's weight (which changes the bounced light alike); the points
    are those of the partial reading."""
    labels, names = ctx.labels["near"], ctx.label_names
    R = _mitsuba(74)
    bounce = dict(ctx.explain.extra["bounce"])[("disk_radius_u", "every")]
    S = R + bounce + np.where((labels == names.index("the floor"))[..., None], 0.05 * R, 0.0)
    res = grade_image("disk_radius_and_floor", ctx, [S], spp=1024)
    ex = res.details["explanation"]
    assert ex["verdict"] == "partial" and ex["broader"] == "diffuse_bounce", ex["sentence"]
    assert "point to the diffuse bounce" in ex["sentence"] and "indirect_scale" in named_causes(res)[0]
    assert "roulette" in named_causes(res)[0] and "Russian roulette's survival probability" in ex["sentence"]
    assert res.score < res.max_score


def test_a_bounce_is_not_said_where_the_light_seen_differs(ctx):
    """The rule on its own (mcrt.grade.broader.reading): a bounce mistake leading a partial reading says the diffuse
    bounce where what is left lies on the room's surfaces; left on the light's own pixels too, which no bounce
    changes, nothing broader is said."""
    from mcrt.grade.broader import reading
    from mcrt.grade.candidates import Candidate

    R = _mitsuba(72)
    labels, names = ctx.labels["near"], ctx.label_names
    var = ctx.model_var["near"].astype(np.float64) / 1024
    mask = np.ones(R.shape[:2], bool)
    lead = Candidate("catalogue", "ball_plus_normal", "Lambertian directions from a random point inside the unit ball",
                     0.0, 0, catalogue=True, change=np.zeros_like(R))
    floor, light = names.index("the floor"), names.index("the light")
    rest = np.zeros_like(R)
    assert reading(lead, rest, R, mask, var, labels, names, [floor, light]) is None
    fam, words = reading(lead, rest, R, mask, var, labels, names, [floor])
    assert fam == "diffuse_bounce" and "the diffuse bounce" in words
    other = Candidate("catalogue", "rr_no_divide", "Russian roulette without dividing", 0.0, 0, catalogue=True,
                      change=np.zeros_like(R))
    assert reading(other, rest, R, mask, var, labels, names, [floor]) is None


def test_a_matrix_near_one_gain_mixes_no_colour(ctx):
    """The free 3x3 colour matrix (mcrt.grade.explain.colour) on a Mitsuba render (seed 73) through matrices: one
    within a few thousandths of 1.01 times the identity is no candidate (no colour changed: such a fit only bends to
    values an encoding or a curve changed); a white balance of a few per cent per channel is, and is fitted."""
    from mcrt.grade.candidates import Inputs
    from mcrt.grade.explain.colour import colour
    from mcrt.grade.explain.fit import Fit

    X = _mitsuba(73)
    R = ctx.references["near"].mean.astype(np.float64)
    V = ctx.model_var["near"].astype(np.float64) / 1024

    def free(M):
        fit = Fit(X @ np.asarray(M).T, R, V, np.ones(R.shape, bool), ctx.explain.var.astype(np.float64) / ctx.explain.spp)
        return next((c for c in colour(fit, Inputs(ctx.explain)) if c.name == "colour matrix"), None)

    assert free([[1.01, 0.002, -0.001], [0.003, 1.008, 0.0], [0.0, -0.002, 1.012]]) is None
    c = free(np.diag([1.06, 1.0, 0.9]))
    assert c is not None and np.allclose(np.diag(c.value["matrix"]), [1.06, 1.0, 0.9], atol=0.02), c.value


def test_an_image_of_one_value_is_said_to_hold_no_view(ctx):
    """A hand-in that is one value everywhere but for its noise (a Mitsuba render's mean in every pixel, seed 74, plus
    noise of its size): no view of the scene is left. A monotone curve describes it only by mapping every value to
    that one (mcrt.grade.feedback.flat_level), and the words say the image holds no view, not that the values went
    through a curve; no cause is claimed, and the image loses points. A curve that bends the values is no such image."""
    from mcrt.grade.feedback import flat_level

    X = _mitsuba(74)
    rng = np.random.default_rng(74)
    S = np.full_like(X, float(X.mean())) * (1.0 + 0.02 * rng.standard_normal(X.shape))
    res = grade_image("one_value", ctx, [S], spp=1024)
    ex = res.details["explanation"]
    assert ex["named"] is None and "nearly one value everywhere" in ex["sentence"], ex["sentence"]
    assert res.score < res.max_score
    assert flat_level({"maps": [[0.03, 0.02], [0.1, 0.021], [20.0, 0.023]]}) == pytest.approx(0.021)
    assert flat_level({"maps": [[0.03, 0.02], [0.1, 0.12], [20.0, 0.98]]}) is None


def _sphere_normals_inward(d, seg=48, rings=24):
    """The Mitsuba scene dictionary with the mirror sphere as a UV mesh whose vertex normals point into it: a mirror
    reflecting about wrong normals (the shading normal flipped), its surface where the sphere's is."""
    import mitsuba as mi

    sph = next(iter(load_scene().spheres()))
    c, r = np.asarray(sph.center, float), float(sph.radius)
    t, p = np.meshgrid(np.linspace(0, np.pi, rings + 1), np.linspace(0, 2 * np.pi, seg + 1), indexing="ij")
    u = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    k = (np.arange(rings)[:, None] * (seg + 1) + np.arange(seg)[None, :]).ravel()
    faces = np.concatenate([np.stack([k, k + seg + 1, k + seg + 2], 1), np.stack([k, k + seg + 2, k + 1], 1)])
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(d["sphere"]["bsdf"])
    mesh = mi.Mesh("sphere", len(u), len(faces), props, has_vertex_normals=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float((c + r * u).reshape(-1).astype(np.float32))
    params["vertex_normals"] = mi.Float((-u).reshape(-1).astype(np.float32))
    params["faces"] = mi.UInt32(faces.astype(np.uint32).reshape(-1))
    params.update()
    return {**d, "sphere": mesh}


def test_a_mirror_reflecting_about_wrong_normals_is_named_with_its_normals(ctx):
    """The mirror sphere with its shading normals pointing inward (Mitsuba, seed 85): black, as the catalogue's
    reflection of the wrong sign leaves it; the image cannot tell the reflection's code from the normals it reflects
    about, and the words name both (and a mesh that is not the sphere)."""
    res = grade_image("normals_in", ctx, [_mitsuba(85, mitsuba_edit=_sphere_normals_inward)], spp=1024)
    fam, said = _claimed(res)
    assert fam is not None and {"normals", "object_shape"} <= set(named_causes(res)[0]), said
    assert "it reflects about its normals" in said and res.score < res.max_score


def test_paths_cut_short_name_the_roulette_that_would_cut_them_too(ctx):
    """Mitsuba's paths cut at depth 3 (seed 86): the depth is claimed, and the words name the light past it lost to
    Russian roulette as well, which gives the same image; paths longer than asked name no roulette."""
    r = _render_spec(Spec("t", None, spp=1024), load_scene(), width=RES, height=RES, max_depth=3, seed=86)
    res = grade_image("depth3", ctx, [np.asarray(r.mean, np.float64)], spp=1024)
    fam, said = _claimed(res)
    assert fam == "depth" and {"depth", "roulette"} <= set(named_causes(res)[0]), said
    assert "paths cut at depth 3" in said and "Russian roulette from there" in said
    from mcrt.grade.explain.scene import _node_candidate

    for longer in (12, -1):
        assert "roulette" not in _node_candidate("depth", longer, 0.0, {}, 8).text
