"""The film read back with another memory layout (mcrt.grade.explain.stride), graded end to end.

The hand-ins are 8-bit and float files of Mitsuba renders (fixed seeds),
written here the way students' programs write them, not by the family's
own functions: a strided view of the codes with the width for the row
stride (as stb_image_write reads them), numpy's bytes of an RGBA array or
of a column-major one, a float buffer with padded rows copied as if
packed, a loop whose row length is one short.
"""

from __future__ import annotations

import OpenEXR
import numpy as np
import pytest
from test_diagnose import RES
from test_feedback import ctx  # noqa: F401 (the 32x32 assignment's context, a fixture)
from test_feedback import _grade_file, _mitsuba, _srgb8

from mcrt.grade.accuracy.run import named_causes
from mcrt.grade.grader import grade_image
from mcrt.scene import load_scene


@pytest.fixture(scope="module")
def render():
    """A Mitsuba render, seed 95, 1024 spp."""
    return _mitsuba(load_scene(), 95)


def _ppm(codes: np.ndarray | bytes) -> bytes:
    return f"P6\n{RES} {RES}\n255\n".encode() + bytes(codes)


def _png_stride_in_pixels(x, tmp):
    """The codes saved the way stbi_write_png(name, W, H, 3, data, W) reads them, its stride in bytes given the width
    (W for 3 W): rows a strided view of the buffer, W bytes apart."""
    from PIL import Image

    flat = _srgb8(x).reshape(-1)
    rows = np.lib.stride_tricks.as_strided(flat, shape=(RES, 3 * RES), strides=(RES, 1), writeable=False)
    path = tmp / "render.png"
    Image.fromarray(np.ascontiguousarray(rows).reshape(RES, RES, 3)).save(path)
    return "render.png", path.read_bytes()


def _ppm_rgba_as_rgb(x, tmp):
    """An RGBA array (alpha 255) whose bytes go out under an RGB header, cut to the header's size."""
    rgba = np.concatenate([_srgb8(x), np.full((RES, RES, 1), 255, np.uint8)], axis=2)
    return "render.ppm", _ppm(rgba.tobytes()[: RES * RES * 3])


def _ppm_column_major(x, tmp):
    """An H x W x 3 array's bytes in Fortran order (as MATLAB's fwrite writes its memory)."""
    return "render.ppm", _ppm(_srgb8(x).tobytes(order="F"))


def _exr_pitched(x, tmp):
    """A float32 film whose rows are padded to 512 bytes (128 floats for 96) copied back as packed rows."""
    dev = np.zeros((RES, 128), np.float32)
    dev[:, : 3 * RES] = x.reshape(RES, 3 * RES)
    packed = dev.reshape(-1)[: RES * RES * 3].reshape(RES, RES, 3)
    path = tmp / "render.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {c: np.ascontiguousarray(packed[..., i]) for i, c in enumerate("RGB")}).write(str(path))
    return "render.exr", path.read_bytes()


def _ppm_row_one_short(x, tmp):
    """Pixel (x, y) written at y * (W - 1) + x by a loop over the rows in order."""
    codes = _srgb8(x)
    flat = np.zeros((RES * RES, 3), np.uint8)
    for y in range(RES):
        for i in range(RES):
            flat[y * (RES - 1) + i] = codes[y, i]
    return "render.ppm", _ppm(flat.tobytes())


@pytest.mark.parametrize("write, words", [
    (_png_stride_in_pixels, "a row stride given in pixels"),
    (_ppm_rgba_as_rgb, "each pixel stored as 4 samples (an RGBA or vec4 film, alpha 1) and read as 3"),
    (_ppm_column_major, "written in column-major order"),
    (_exr_pitched, "each row padded to 128 samples (32 after its 96"),
    (_ppm_row_one_short, f"pixel (x, y) written at y * {RES - 1} + x"),
])
def test_a_film_read_with_another_layout_is_claimed(ctx, render, tmp_path, write, words):
    """Each layout mistake is claimed in its own words (what is left is noise) and named as the row stride; an 8-bit
    file is not blamed for its encoding as well (the curve the moved values fit best is no evidence of one)."""
    name, data = write(render, tmp_path)
    res = _grade_file(ctx, tmp_path / "hand_in", name, data)
    ex = res.details["explanation"]
    assert ex["verdict"] == "claimed" and ex["family"] == "stride", ex["sentence"]
    assert words in ex["sentence"], ex["sentence"]
    assert named_causes(res)[0] == ["row_stride"]
    assert next(t for t in res.tests if t.name == "linear").status == "passed"
    assert res.score <= 0.75 * res.max_score


def test_a_darker_render_is_no_layout(ctx, render):
    """The same render at half its brightness: a layout's zeros darken too and take up a share of it, but the scale
    is claimed and no layout is named, not even as the closest."""
    res = grade_image("half", ctx, [0.5 * render], spp=1024)
    ex = res.details["explanation"]
    assert ex["family"] != "stride" and "another memory layout" not in ex["sentence"], ex["sentence"]
    assert "row_stride" not in named_causes(res)[0]


def test_values_moved_by_a_layout_do_not_blame_the_encoding(ctx, tmp_path):
    """A column-major PPM of another render (seed 96): its values, at other places, fit a gamma of 2.4 better than
    the sRGB curve its format declares (the linear criterion failed on it before moved values were ruled out). The
    layout is claimed, and decoded as declared the image is that layout and noise: the encoding is not blamed, and
    the file is graded decoded as declared. Read through the gamma of 2.4, the bias test found few of its tiles and
    left it part of its points; decoded as declared, the whole film is moved, and it keeps none."""
    name, data = _ppm_column_major(_mitsuba(load_scene(), 96), tmp_path)
    res = _grade_file(ctx, tmp_path / "hand_in", name, data)
    ex = res.details["explanation"]
    assert ex["verdict"] == "claimed" and ex["family"] == "stride", ex["sentence"]
    tests = {t.name: t for t in res.tests}
    assert tests["linear"].status == "passed" and tests["linear"].output.startswith("encoded as declared"), \
        tests["linear"].output
    assert "a gamma of 2.4" in tests["linear"].output
    assert (res.details["encoding"]["detected"], res.details["encoding"]["fitted"]) == ("srgb", "gamma2.4")
    assert tests["unbiased"].score == 0, tests["unbiased"].output
    assert named_causes(res)[0] == ["row_stride"]
