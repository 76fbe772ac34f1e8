"""File mistakes named at intake and calibration (issue 27): a PFM header declaring the other byte order, a 16-bit PNG
little-endian or holding 8-bit codes times 256, 8-bit codes cast without a clip, linear values rounded to 8 bits
before the sRGB curve, float values rounded to decimals, a PNG of sRGB's exponent alone or of the gamma the wrong way
round, and a pair of renders made with one seed.

The hand-ins are Mitsuba renders (fixed seeds) written the way a student's program writes them; they are graded by
the production grader with the 32x32 assignment of test_diagnose, prepared once per module in the run's cache.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_diagnose import ASSIGNMENT, RES

from mcrt.grade.accuracy.cases import Spec, _render_spec
from mcrt.grade.accuracy.run import named_causes
from mcrt.grade.assignment import assignment_from_dict
from mcrt.grade.expected import prepare_context
from mcrt.grade.grader import grade_submission
from mcrt.grade.stages.intake import implausible_share
from mcrt.grade.stages.noise import SAME_PAIR_RATIO, same_pair
from mcrt.grade.submissions import discover
from mcrt.image_files import read_pfm, write_pfm
from mcrt.scene import load_scene


@pytest.fixture(scope="module")
def ctx(tmp_path_factory, grade_cache):
    a = assignment_from_dict(ASSIGNMENT, str(tmp_path_factory.mktemp("intake") / "explain32.toml"))
    return prepare_context(a, grade_cache)


@pytest.fixture(scope="module")
def renders():
    """Two Mitsuba renders at 256 spp, seeds 31 and 32."""
    scene = load_scene()
    return [_render_spec(Spec("t", None, spp=256), scene, width=RES, height=RES, max_depth=8, seed=s).mean
            for s in (31, 32)]


def _pfm(path, img, scale: str, order: str) -> None:
    """A PFM as a student's program writes it: header with ``scale``, rows bottom to top, floats in ``order``."""
    h, w = img.shape[:2]
    path.write_bytes(f"PF\n{w} {h}\n{scale}\n".encode() + np.ascontiguousarray(img[::-1], order + "f4").tobytes())


def _grade(ctx, folder, files: dict, spp: int = 256):
    folder.mkdir()
    for name, write in files.items():
        write(folder / name)
    (folder / "manifest.toml").write_text(f"spp = {spp}\n")
    return grade_submission(discover(folder, single=True, student=folder.name)[0], ctx)


def _test(res, name):
    return next(t for t in res.tests if t.name == name)


# --------------------------------------------------------------------------
# The PFM's byte order
# --------------------------------------------------------------------------


def test_little_endian_data_under_a_big_endian_header_is_read_swapped_and_named(ctx, renders, tmp_path):
    """Header scale 1.0 over little-endian floats (x86): read per the spec the values are garbage; the grader reads
    them little-endian, grades that render (full marks on the bias test) and names the file mistake."""
    img = renders[0]
    p = tmp_path / "raw.pfm"
    _pfm(p, img, "1.0", "<")
    assert implausible_share(read_pfm(p)) > 0.1  # per the spec: garbage (NaN, huge and tiny values)
    res = _grade(ctx, tmp_path / "student", {"render.pfm": lambda q: _pfm(q, img, "1.0", "<")})
    readable = _test(res, "readable")
    assert readable.status == "failed" and readable.score == 0
    assert "header scale 1.0 declares big-endian data, but the data are little-endian" in readable.output
    assert "write -1.0 (little-endian) in the header" in readable.output
    assert _test(res, "finite").status == "passed"
    assert _test(res, "unbiased").status == "passed"
    assert res.score == res.max_score - readable.max_score
    named, _ = named_causes(res)
    assert named == ["file_format"]


@pytest.mark.parametrize("scale, order", [("1.0", ">"), ("-1.0", "<")])
def test_a_pfm_whose_header_matches_its_data_is_unaffected(ctx, renders, tmp_path, scale, order):
    res = _grade(ctx, tmp_path / "student", {"render.pfm": lambda q: _pfm(q, renders[0], scale, order)})
    assert _test(res, "readable").status == "passed"
    assert "byte_order" not in res.details
    assert res.score == res.max_score
    assert named_causes(res)[0] == []


def test_a_pfm_with_some_nan_pixels_is_not_taken_for_a_byte_order_mistake(ctx, renders, tmp_path):
    """A correct little-endian PFM with 2 % of its pixels NaN (a renderer's bug): the other byte order is no more
    plausible, so the NaN pixels are reported as such."""
    img = renders[0].astype(np.float32).copy()
    img[::7, ::7] = np.nan
    res = _grade(ctx, tmp_path / "student", {"render.pfm": lambda q: _pfm(q, img, "-1.0", "<")})
    assert _test(res, "readable").status == "passed" and "byte_order" not in res.details
    assert _test(res, "finite").status == "failed"


def _png16(path, img, byteorder: str) -> None:
    """A 16-bit sRGB PNG written by hand (pypng's writer given the samples in ``byteorder``, as a program that
    writes a uint16 buffer as it lies in memory does)."""
    import png

    from mcrt.image_files import srgb_oetf

    codes = np.floor(np.clip(srgb_oetf(img), 0, 1) * 65535 + 0.5).astype(np.uint16)
    if byteorder == "<":
        codes = codes.byteswap()
    h, w = codes.shape[:2]
    with open(path, "wb") as f:
        png.Writer(w, h, greyscale=False, bitdepth=16).write(f, codes.reshape(h, w * 3).tolist())


@pytest.mark.parametrize("order", [">", "<"])
def test_a_png16_written_little_endian_is_read_swapped_and_named(ctx, renders, tmp_path, order):
    """A 16-bit PNG whose samples are little-endian resembles no view as read: the grader reads it byte-swapped,
    grades that render and names the file mistake; a big-endian one (the spec) is left alone."""
    res = _grade(ctx, tmp_path / "student", {"render.png": lambda q: _png16(q, renders[0], order)})
    readable = _test(res, "readable")
    if order == "<":
        assert readable.status == "failed" and "samples are little-endian" in readable.output, readable.output
        assert named_causes(res)[0] == ["file_format"]
    else:
        assert readable.status == "passed" and "byte_order" not in res.details
    assert _test(res, "unbiased").status == "passed"


def _png16_of_codes(path, img, times: int) -> None:
    """A 16-bit PNG of 8-bit sRGB codes times ``times`` (257 fills 0 to 65535; 256, a shift by 8 bits, stops at
    65280), written with pypng."""
    import png

    from mcrt.image_files import srgb_oetf

    codes = np.rint(np.clip(srgb_oetf(img), 0, 1) * 255).astype(np.uint16) * times
    h, w = codes.shape[:2]
    with open(path, "wb") as f:
        png.Writer(w, h, greyscale=False, bitdepth=16).write(f, codes.reshape(h, w * 3).tolist())


@pytest.mark.parametrize("times", [256, 257])
def test_8bit_codes_times_256_in_a_16bit_png_are_named(ctx, renders, tmp_path, times):
    """Every code a multiple of 256: the 8-bit codes shifted by 8 bits (white 65280), named under ``linear`` and graded
    as the 8-bit codes they are; times 257 is the exact widening, and passes."""
    res = _grade(ctx, tmp_path / "student", {"render.png": lambda q: _png16_of_codes(q, renders[0], times)})
    linear = _test(res, "linear")
    if times == 256:
        assert linear.status == "failed" and "8-bit codes times 256" in linear.output, linear.output
        assert res.details["encoding"]["codes"] == ["times_256"] and named_causes(res)[0] == ["encoding"]
    else:
        assert linear.status == "passed" and "codes" not in res.details["encoding"]
    assert _test(res, "unbiased").status == "passed"


@pytest.mark.parametrize("clip", [False, True])
def test_8bit_codes_cast_without_a_clip_are_named(ctx, renders, tmp_path, clip):
    """``(v * 255).astype(np.uint8)`` without a clip: the light's pixels (20, far above 1) wrap round to code 155;
    with the clip they are white and nothing is said."""
    from PIL import Image

    from mcrt.image_files import srgb_oetf

    def write(q):
        v = srgb_oetf(np.maximum(renders[0], 0.0))
        v = np.clip(v, 0, 1) if clip else v
        Image.fromarray((np.rint(v * 255).astype(np.int64) % 256).astype(np.uint8), "RGB").save(q)

    res = _grade(ctx, tmp_path / "student", {"render.png": write})
    linear = _test(res, "linear")
    if clip:
        assert linear.status == "passed" and res.score == res.max_score
    else:
        assert linear.status == "failed" and "wrap round past 255" in linear.output, linear.output
        assert res.details["encoding"]["codes"] == ["wrapped"] and "encoding" in named_causes(res)[0]


@pytest.mark.parametrize("scale", [256, 255, "interp1d"])
def test_white_that_overflows_to_0_is_named(ctx, renders, tmp_path, scale):
    """``np.clip(v, 0, 1) * 256`` cast to uint8: white (the light, far above 1) is 256 and wraps to 0, every other
    code is kept or one up; the light's pixels are left out of every statistic of an 8-bit file, so only the codes
    show it. Named under ``linear`` (an overflow, a NaN cast, or pixels never drawn); scaled by 255, nothing is said.
    The sRGB curve looked up with SciPy's interp1d on a table from 0 to 1 (its NaN fill value past the end, cast to
    0 as x86 casts it) gives the same codes, and its words name the NaN too."""
    from PIL import Image
    from scipy.interpolate import interp1d

    from mcrt.image_files import srgb_oetf

    def write(q):
        if scale == "interp1d":
            table = np.linspace(0.0, 1.0, 256)
            v = interp1d(table, srgb_oetf(table), bounds_error=False)(np.maximum(renders[0], 0.0))
            Image.fromarray(np.nan_to_num(np.round(v * 255.0), nan=0.0).astype(np.uint8), "RGB").save(q)
            return
        v = np.clip(srgb_oetf(np.maximum(renders[0], 0.0)), 0, 1)
        Image.fromarray((np.floor(v * scale).astype(np.int64) % 256).astype(np.uint8), "RGB").save(q)

    res = _grade(ctx, tmp_path / "student", {"render.png": write})
    linear = _test(res, "linear")
    if scale == 255:
        assert linear.status == "passed" and "codes" not in res.details["encoding"], linear.output
    else:
        assert linear.status == "failed" and "hold 0: the top code overflowed" in linear.output, linear.output
        assert res.details["encoding"]["codes"] == ["white_zero"] and "encoding" in named_causes(res)[0]
        assert "bad_pixels" in named_causes(res)[0] and res.score < res.max_score


@pytest.mark.parametrize("first", ["rounded", "encoded", "cast"])
def test_linear_values_rounded_to_8_bits_before_the_curve_are_named(ctx, renders, tmp_path, first):
    """A 256-entry sRGB table applied to linear values rounded to 8 bits: no dark code but 13, 22, 28, ...; the bias
    test alone does not see it (the rounding averages out). Encoded from the floats, then rounded, nothing is said.
    Cast to integers before the scaling by 255, every code is 0 or 255, and the words say so."""
    from PIL import Image

    from mcrt.image_files import srgb_oetf

    def write(q):
        if first == "cast":  # the encoded values clipped, cast, then scaled: the light alone reaches 1
            c = np.clip(srgb_oetf(np.maximum(renders[0], 0)), 0, 1).astype(np.uint8) * 255
        else:
            v = np.clip(renders[0], 0, 1)
            v = np.rint(v * 255) / 255 if first == "rounded" else v
            c = np.rint(srgb_oetf(v) * 255).astype(np.uint8)
        Image.fromarray(c, "RGB").save(q)

    res = _grade(ctx, tmp_path / "student", {"render.png": write})
    linear = _test(res, "linear")
    if first == "encoded":
        assert linear.status == "passed" and "codes" not in res.details["encoding"], linear.output
    else:
        words, code = {"rounded": ("rounded to 8 bits before the curve", "rounded_first"),
                       "cast": ("cast to integers before they were scaled", "cast_first")}[first]
        assert linear.status == "failed" and words in linear.output, linear.output
        assert code in res.details["encoding"]["codes"] and "encoding" in named_causes(res)[0]
        assert res.score < res.max_score


@pytest.mark.parametrize("decimals", [2, None])
def test_values_rounded_to_decimals_are_named(ctx, renders, tmp_path, decimals):
    """A float file of np.round(render, 2): every value a multiple of 0.01, which the bias test does not see (the
    rounding averages out); named under the linear criterion. The render as it is: nothing said."""
    from mcrt.image_files import write_pfm

    img = renders[0] if decimals is None else np.round(renders[0], decimals)
    res = _grade(ctx, tmp_path / "student", {"render.pfm": lambda q: write_pfm(q, img.astype(np.float32))})
    linear = _test(res, "linear")
    if decimals is None:
        assert linear.status == "passed" and "codes" not in res.details["encoding"], linear.output
    else:
        assert linear.status == "failed" and "rounded to 2 decimals" in linear.output, linear.output
        assert res.details["encoding"]["codes"] == ["decimals_2"] and "encoding" in named_causes(res)[0]
        assert res.score < res.max_score


def test_a_png_of_the_srgb_exponent_alone_loses_the_encoding_points(ctx, renders, tmp_path):
    """An 8-bit PNG of v ** (1 / 2.4) (sRGB's exponent without its linear segment): the curve is found and named, and
    it loses the criterion's points although the course accepts a gamma of 2.2 (png_gamma_loss 0)."""
    from PIL import Image

    codes = np.rint(np.clip(renders[0], 0, 1) ** (1 / 2.4) * 255).astype(np.uint8)
    res = _grade(ctx, tmp_path / "student", {"render.png": lambda q: Image.fromarray(codes, "RGB").save(q)})
    linear = _test(res, "linear")
    assert res.details["encoding"]["detected"] == "gamma2.4"
    assert linear.status == "failed" and "a gamma of 2.4" in linear.output and "encoding" in named_causes(res)[0]
    assert res.score < res.max_score


def test_a_png_of_the_gamma_applied_the_wrong_way_round_is_named(ctx, renders, tmp_path):
    """An 8-bit PNG of v ** 2.2 (the display gamma applied where its inverse belongs; Pillow writes it): the curve is
    found and named under the encoding criterion, not taken for linear values rounded before the curve (a darkening
    curve reaches every dark code), and the criterion's points are lost."""
    from PIL import Image

    codes = np.rint(np.clip(renders[0], 0, 1) ** 2.2 * 255).astype(np.uint8)
    res = _grade(ctx, tmp_path / "student", {"render.png": lambda q: Image.fromarray(codes, "RGB").save(q)})
    linear = _test(res, "linear")
    assert res.details["encoding"]["detected"] == "inverted2.2" and "codes" not in res.details["encoding"]
    assert linear.status == "failed" and "the gamma applied the wrong way round" in linear.output
    assert "encoding" in named_causes(res)[0] and res.score < res.max_score


def test_implausible_share_counts_what_no_radiance_is():
    x = np.array([0.0, 1e-3, 20.0, -0.01, np.nan, np.inf, 1e31, 1e-35, 1e-40], np.float64)
    assert implausible_share(x) == pytest.approx(5 / 9)


# --------------------------------------------------------------------------
# Two renders with one seed
# --------------------------------------------------------------------------


def test_an_identical_pair_is_named_and_the_model_noise_used(ctx, renders, tmp_path):
    img = renders[0]
    files = {f"render_{k}.pfm": (lambda q: write_pfm(q, img)) for k in (1, 2)}
    res = _grade(ctx, tmp_path / "student", files, spp=256)
    noise = _test(res, "noise")
    assert noise.status == "failed" and noise.score == 0
    assert noise.output.startswith("your two renders are identical: render them with different seeds")
    assert "the noise was taken from the model of one render instead" in noise.output
    assert res.details["noise"]["renders"] == 1
    assert _test(res, "unbiased").status == "passed"
    assert res.score == res.max_score - noise.max_score
    assert named_causes(res)[0] == ["same_seed"]


def test_a_proper_pair_is_not_named(ctx, renders, tmp_path):
    files = {f"render_{k}.pfm": (lambda q, k=k: write_pfm(q, renders[k - 1])) for k in (1, 2)}
    res = _grade(ctx, tmp_path / "student", files, spp=256)
    assert _test(res, "noise").status == "passed"
    assert res.details["pair"]["same_noise"] is False and res.details["noise"]["renders"] == 2
    assert res.score == res.max_score
    assert named_causes(res)[0] == []


def test_same_pair_measures_shared_noise(ctx, renders):
    """The ratio is about 1 or more for independent renders (seeds 31, 32: Mitsuba's noise is heavy-tailed), far
    below the limit for renders whose noise is correlated by 0.99, and 0 for identical ones."""
    a, b = (np.asarray(r, np.float64) for r in renders)
    ref = ctx.references["near"]
    R = ref.mean.astype(np.float64)
    var = ctx.model_var["near"] / 256 + ref.var / ref.spp
    mask, labels = np.ones((RES, RES), bool), ctx.labels["near"]
    same, ratio = same_pair(a, b, R, var, mask, labels)
    assert not same and 0.7 < ratio < 3.0
    # b' = 0.9 a + 0.1 b: its noise is correlated with a's by 0.99 (its difference from a: 0.01 of two renders')
    same, ratio = same_pair(a, a + 0.1 * (b - a), R, var, mask, labels)
    assert same and ratio < SAME_PAIR_RATIO
    assert same_pair(a, a.copy(), R, var, mask, labels) == (True, 0.0)
