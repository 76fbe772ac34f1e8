"""Image input and output: EXR with provenance, PFM, Radiance HDR, PNG, previews."""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np
import OpenEXR
import pytest
from PIL import Image

from mcrt import image_files
from mcrt.image_files import ImageError, read_exr, read_hdr, read_image, read_pfm, read_png, tonemap, write_exr, write_hdr, write_pfm
from mcrt.film import RenderResult

# Fixed seed: the test images are arbitrary but must be the same every run.
RNG_SEED = 20240611


def rng() -> np.random.Generator:
    return np.random.default_rng(RNG_SEED)


def make_result(h: int = 24, w: int = 32, variance: bool = True) -> RenderResult:
    g = rng()
    mean = g.lognormal(-1.0, 2.0, (h, w, 3)).astype(np.float32)
    mean[0, 0] = [np.nan, np.inf, -0.0]  # specials must survive bit-exactly
    var = g.random((h, w, 3), dtype=np.float32) if variance else None
    return RenderResult(
        mean=mean,
        variance=var,
        spp=1024,
        seed=2**40 + 7,  # does not fit an EXR int attribute
        max_depth=-1,
        renderer="mcrt",
        scene_hash="9f86d081884c7d65",
        camera="pinhole fov=45 eye=(0,-3,1)",
        wall_time=12.345678901234567,  # needs a double attribute
        compile_time=0.1,
        extra={"mutant": "none", "merged_seeds": "1,2,3", "note": "héllo wörld"},
    )


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, np.float32).view(np.uint32)


# --------------------------------------------------------------------------
# EXR
# --------------------------------------------------------------------------


def test_exr_round_trip_is_exact(tmp_path):
    r = make_result()
    path = tmp_path / "r.exr"
    write_exr(path, r)
    back = read_exr(path)
    np.testing.assert_array_equal(bits(back.mean), bits(r.mean))
    np.testing.assert_array_equal(bits(back.variance), bits(r.variance))
    for name in ("spp", "seed", "max_depth", "renderer", "scene_hash", "camera", "wall_time", "compile_time", "extra"):
        assert getattr(back, name) == getattr(r, name), name
    assert back.mean.dtype == np.float32 and back.mean.shape == (24, 32, 3)


def test_exr_file_layout(tmp_path):
    """The file itself has the documented channels and attribute types."""
    path = tmp_path / "r.exr"
    write_exr(path, make_result())
    f = OpenEXR.File(str(path), separate_channels=True)
    assert sorted(f.channels()) == ["B", "G", "R", "variance.B", "variance.G", "variance.R"]
    assert all(c.pixels.dtype == np.float32 for c in f.channels().values())
    h = f.header()
    assert h["compression"] in (OpenEXR.ZIP_COMPRESSION, OpenEXR.PIZ_COMPRESSION)
    assert h["spp"] == 1024 and h["max_depth"] == -1 and h["renderer"] == "mcrt"
    assert h["wall_time"].dtype == np.float64  # a double, not a 32-bit float
    assert h["mcrt.mutant"] == "none"


def test_exr_without_variance_or_compile_time(tmp_path):
    r = make_result(variance=False)
    r.compile_time = None
    r.extra = {}
    path = tmp_path / "r.exr"
    write_exr(path, r)
    back = read_exr(path)
    assert back.variance is None and back.compile_time is None and back.extra == {}
    assert sorted(OpenEXR.File(str(path), separate_channels=True).channels()) == ["B", "G", "R"]


def test_read_plain_half_rgb_exr(tmp_path):
    g = rng()
    planes = {c: g.random((10, 12)).astype(np.float16) for c in "RGB"}
    path = tmp_path / "plain.exr"
    # dict(...): the binding replaces the arrays in the dict it is given by Channel objects
    OpenEXR.File({"compression": OpenEXR.PIZ_COMPRESSION, "type": OpenEXR.scanlineimage}, dict(planes)).write(str(path))
    r = read_exr(path)
    np.testing.assert_array_equal(r.mean, np.stack([planes[c].astype(np.float32) for c in "RGB"], axis=-1))
    assert r.mean.dtype == np.float32
    assert (r.spp, r.variance, r.renderer, r.compile_time, r.extra) == (0, None, "unknown", None, {})


def test_read_rgba_float_exr_ignores_alpha(tmp_path):
    g = rng()
    planes = {c: g.random((7, 5)).astype(np.float32) for c in "RGBA"}
    path = tmp_path / "rgba.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, dict(planes)).write(str(path))
    r = read_exr(path)
    np.testing.assert_array_equal(r.mean, np.stack([planes[c] for c in "RGB"], axis=-1))
    assert r.spp == 0 and r.variance is None and "exr.ignored_channels" not in r.extra


def test_y_only_exr_names_channels(tmp_path):
    path = tmp_path / "grey.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, {"Y": np.ones((4, 4), np.float32), "Z": np.zeros((4, 4), np.float32)}).write(str(path))
    with pytest.raises(ImageError) as e:
        read_exr(path)
    msg = str(e.value)
    assert "grey.exr" in msg and "Y, Z" in msg and "\n" not in msg



def _moment_exr(path, m1, m2, header=None):
    """An EXR laid out as Mitsuba's 'moment' integrator writes it: R, G, B and the nested XYZ moments."""
    rgb = m1 @ image_files.XYZ_TO_RGB.T
    ch = {c: np.ascontiguousarray(rgb[..., i], np.float32) for i, c in enumerate("RGB")}
    for i, c in enumerate("XYZ"):
        ch[f"nested.{c}"] = np.ascontiguousarray(m1[..., i], np.float32)
        ch[f"m2_nested.{c}"] = np.ascontiguousarray(m2[..., i], np.float32)
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **(header or {})}, ch).write(str(path))


def test_read_mitsuba_moment_exr(tmp_path):
    """nested.X/Y/Z and m2_nested.X/Y/Z: mean by the XYZ -> linear sRGB matrix, variance (m2 - m1^2) n / (n - 1), bounded."""
    g = rng()
    m1 = g.uniform(0.1, 1.0, (6, 5, 3))
    var_xyz = g.uniform(0.01, 0.2, (6, 5, 3))
    n = 64
    m2 = var_xyz * (n - 1) / n + m1 * m1  # what a film of n samples holds
    _moment_exr(tmp_path / "m.exr", m1, m2)
    r = read_exr(tmp_path / "m.exr", spp=n)
    M = image_files.XYZ_TO_RGB
    assert np.allclose(M, [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]])
    assert r.spp == n and np.allclose(r.mean, m1 @ M.T, rtol=1e-5, atol=1e-6)
    assert np.allclose(r.variance, (np.sqrt(var_xyz) @ np.abs(M).T) ** 2, rtol=1e-3)
    assert "n = 64" in r.extra["exr.moment"] and "exr.ignored_channels" not in r.extra
    # Without spp the factor n / (n - 1) cannot be applied: noted, and spp stays unknown (0).
    u = read_exr(tmp_path / "m.exr")
    assert u.spp == 0 and "spp unknown" in u.extra["exr.moment"] and np.all(u.variance < r.variance)
    # A file that records its spp needs none given.
    _moment_exr(tmp_path / "s.exr", m1, m2, {"spp": n})
    assert np.array_equal(read_exr(tmp_path / "s.exr").variance, r.variance)
    # Incomplete moments are named.
    ch = {"nested.X": np.ones((2, 2), np.float32), "nested.Y": np.ones((2, 2), np.float32)}
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, ch).write(str(tmp_path / "i.exr"))
    with pytest.raises(ImageError, match="incomplete moment channels, missing nested.Z"):
        read_exr(tmp_path / "i.exr")


@pytest.mark.parametrize("fraction", [0.02, 0.5, 0.97])
def test_truncated_exr(tmp_path, fraction):
    path = tmp_path / "cut.exr"
    write_exr(path, make_result(64, 64))
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])
    with pytest.raises(ImageError) as e:
        read_exr(path)
    assert str(e.value).startswith(f"{path}: ") and "truncated" in str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("prefix", [b"", image_files.EXR_MAGIC])
def test_random_bytes_exr(tmp_path, prefix):
    path = tmp_path / "noise.exr"
    path.write_bytes(prefix + rng().integers(0, 256, 5000, dtype=np.uint8).tobytes())
    with pytest.raises(ImageError, match="noise.exr"):
        read_exr(path)


def test_missing_exr(tmp_path):
    with pytest.raises(ImageError, match="nope.exr: no such file"):
        read_image(tmp_path / "nope.exr")


def test_failed_write_keeps_good_file(tmp_path, monkeypatch):
    path = tmp_path / "good.exr"
    write_exr(path, make_result())
    before = path.read_bytes()

    bad = make_result()
    bad.mean = bad.mean[..., :2]  # wrong shape: rejected
    with pytest.raises(ImageError, match="good.exr"):
        write_exr(path, bad)

    def half_write(tmp, header, channels):  # fails after writing part of the file
        with open(tmp, "wb") as f:
            f.write(before[:100])
        raise RuntimeError("disk full")

    monkeypatch.setattr(image_files, "_write_exr_file", half_write)
    with pytest.raises(ImageError, match="disk full"):
        write_exr(path, make_result())
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["good.exr"]


# --------------------------------------------------------------------------
# PFM
# --------------------------------------------------------------------------


def gradient(h: int = 6, w: int = 5) -> np.ndarray:
    """Value 100 * row + 10 * column + channel: any flip or transpose shows."""
    y, x, c = np.meshgrid(np.arange(h), np.arange(w), np.arange(3), indexing="ij")
    return (100.0 * y + 10.0 * x + c).astype(np.float32)


@pytest.mark.parametrize("little", [True, False])
def test_pfm_round_trip_and_layout(tmp_path, little):
    img = gradient()
    path = tmp_path / "g.pfm"
    write_pfm(path, img, little_endian=little)
    data = path.read_bytes()
    head = b"PF\n5 6\n" + (b"-1.0\n" if little else b"1.0\n")
    assert data.startswith(head)
    raw = np.frombuffer(data[len(head):], "<f4" if little else ">f4").reshape(6, 5, 3)
    np.testing.assert_array_equal(raw[0], img[-1])  # first stored row is the bottom row
    np.testing.assert_array_equal(read_pfm(path), img)


@pytest.mark.parametrize("little", [True, False])
def test_pfm_greyscale_is_replicated(tmp_path, little):
    grey = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]], np.float32)  # top row first
    body = grey[::-1].astype("<f4" if little else ">f4").tobytes()
    path = tmp_path / "y.pfm"
    path.write_bytes(b"Pf\n2 3\n" + (b"-1.000000\n" if little else b"1.000000\n") + body)
    out = read_pfm(path)
    assert out.shape == (3, 2, 3)
    for c in range(3):
        np.testing.assert_array_equal(out[..., c], grey)


def test_pfm_truncated(tmp_path):
    path = tmp_path / "t.pfm"
    write_pfm(path, gradient())
    path.write_bytes(path.read_bytes()[:-4])
    with pytest.raises(ImageError, match="t.pfm: truncated"):
        read_pfm(path)


def test_exr_of_integer_channels_is_refused_naming_the_cast(tmp_path):
    """An EXR whose channels are unsigned integers (OpenEXR's UINT, ``image.astype(np.uint32)``): refused with one
    line that names the cast; a float one written the same way is read."""
    import OpenEXR

    path = tmp_path / "t.exr"
    img = gradient()
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {c: np.ascontiguousarray(img[..., i].astype(np.uint32)) for i, c in enumerate("RGB")}).write(
        str(path))
    with pytest.raises(ImageError, match=r"t.exr: channel \w holds uint32 \(integers: the values cast to an integer "
                                         r"type before writing\), expected half or float$"):
        read_image(path)
    OpenEXR.File(header, {c: np.ascontiguousarray(img[..., i]) for i, c in enumerate("RGB")}).write(str(path))
    assert np.array_equal(read_image(path).mean, img)


def test_pfm_with_more_data_than_its_header_declares(tmp_path):
    """An RGB image under a greyscale 'Pf' header (3 times the data) is an error that says so; a writer's trailing
    newline is not."""
    path = tmp_path / "t.pfm"
    img = gradient()
    h, w = img.shape[:2]
    path.write_bytes(f"Pf\n{w} {h}\n-1.0\n".encode() + np.ascontiguousarray(img[::-1], "<f4").tobytes())
    with pytest.raises(ImageError, match="t.pfm: PFM file holds .* more than its header declares .*write the header 'PF'"):
        read_pfm(path)
    write_pfm(path, img)
    path.write_bytes(path.read_bytes() + b"\n")
    np.testing.assert_array_equal(read_pfm(path), img.astype(np.float32))


@pytest.mark.parametrize("maxval", [255, 65535])
def test_ppm_whose_header_ends_with_two_newlines(tmp_path, maxval):
    """A binary PPM written with a newline too many after its header (every sample a byte late, written here by hand)
    is an error that says so, at 8 and 16 bits; the same raster with a trailing newline instead is read right, as is
    one whose first sample is the code of a newline (10) and has no extra byte."""
    codes = np.random.default_rng(7).integers(0, maxval + 1, (5, 6, 3)).astype(">u2" if maxval > 255 else "u1")
    codes[-1, -1, -1] = 200  # the last sample no whitespace code
    codes[0, 0, 0] = 10
    head = f"P6\n6 5\n{maxval}\n".encode()
    path = tmp_path / "t.ppm"
    path.write_bytes(head + b"\n" + codes.tobytes())
    with pytest.raises(ImageError, match="t.ppm: the header is followed by 2 whitespace bytes .* 1 byte late"):
        image_files.read_netpbm(path, linear=True)
    for raw in (head + codes.tobytes() + b"\n", head + codes.tobytes()):
        path.write_bytes(raw)
        img, _ = image_files.read_netpbm(path, linear=True)
        np.testing.assert_allclose(img * maxval, codes.astype(np.float64), atol=1e-3 * maxval / 255)


def test_ppm_holding_an_rgba_buffer_is_refused_naming_it(tmp_path):
    """An 8-bit RGBA buffer written whole under a P6 header (as a program that keeps alpha writes it) is refused with
    words that name the 4 bytes a pixel; the same pixels as RGB are read right."""
    rgba = np.random.default_rng(3).integers(0, 256, (5, 6, 4)).astype("u1")
    head = b"P6\n6 5\n255\n"
    path = tmp_path / "t.ppm"
    path.write_bytes(head + rgba.tobytes())
    with pytest.raises(ImageError, match="t.ppm: .*4 bytes a pixel where its RGB header declares 3: an RGBA buffer"):
        image_files.read_netpbm(path, linear=True)
    path.write_bytes(head + rgba[..., :3].tobytes())
    img, _ = image_files.read_netpbm(path, linear=True)
    np.testing.assert_allclose(img * 255, rgba[..., :3].astype(np.float64), atol=1e-3)


@pytest.mark.parametrize("magic, planes", [("P6", 3), ("P5", 1)])
def test_netpbm_written_as_utf8_text_is_refused_naming_it(tmp_path, magic, planes):
    """8-bit samples written as a str of chr(code) to a file opened with 'w' (UTF-8: each code of 128 or more two
    bytes, as Python writes it on Linux, with and without a trailing newline) are refused with words that name the
    text mode; the same codes as bytes are read right, as is a file whose codes are all below 128 (its text and
    its bytes the same)."""
    codes = np.random.default_rng(4).integers(0, 256, (5, 6, planes)).astype("u1")
    head = f"{magic}\n6 5\n255\n"
    path = tmp_path / "t.ppm"
    for tail in ("", "\n"):
        with open(path, "w", encoding="utf-8") as f:
            f.write(head + "".join(map(chr, codes.reshape(-1).tolist())) + tail)
        with pytest.raises(ImageError, match="t.ppm: the samples were written as text encoded UTF-8 .*'wb'"):
            image_files.read_netpbm(path, linear=True)
    for low in (codes, codes // 2):
        path.write_bytes(head.encode() + low.tobytes())
        img, _ = image_files.read_netpbm(path, linear=True)
        np.testing.assert_allclose(img[..., :planes] * 255, low.astype(np.float64), atol=1e-3)


def test_ppm_with_16_bit_samples_under_an_8_bit_header(tmp_path):
    """16-bit samples written under maxval 255 (twice the data the header declares, written here by hand) are an
    error that names the maxval."""
    codes = np.random.default_rng(8).integers(0, 65536, (5, 6, 3)).astype(">u2")
    path = tmp_path / "t.ppm"
    path.write_bytes(b"P6\n6 5\n255\n" + codes.tobytes())
    with pytest.raises(ImageError, match="t.ppm: the netpbm file holds 2 times the data .* maxval 65535"):
        image_files.read_netpbm(path)


# --------------------------------------------------------------------------
# Radiance HDR
# --------------------------------------------------------------------------


def hdr_test_image() -> np.ndarray:
    g = rng()
    img = g.lognormal(0.0, 3.0, (9, 40, 3))
    img[2, :] = [0.25, 0.5, 1.0]  # a flat row, long runs in RLE
    img[3, 5] = 0.0
    img[4, 7] = [1.0, 0.0, 0.0]
    img[4, 8] = [0.999, 0.7, 0.001]  # 0.999 rounds up to 1.0 = 128/128, a new exponent
    return img.astype(np.float32)


@pytest.mark.parametrize("rle", [True, False])
def test_hdr_round_trip(tmp_path, rle):
    img = hdr_test_image()
    path = tmp_path / "x.hdr"
    write_hdr(path, img, rle=rle)
    back = read_hdr(path)
    assert back.shape == img.shape and back.dtype == np.float32
    # RGBE: 8-bit mantissas sharing the exponent of the largest channel; rounding
    # to nearest keeps the error within half a step, 1/256 of that channel.
    tol = img.max(axis=2, keepdims=True) / 256 * (1 + 1e-6)
    assert np.all(np.abs(back - img) <= tol)
    assert back[3, 5].tolist() == [0, 0, 0] and back[4, 7].tolist() == [1, 0, 0]
    assert back[4, 8].tolist() == [1.0, 90 / 128, 0.0]  # nearest values with exponent 2**1
    np.testing.assert_array_equal(back[2], np.tile([0.25, 0.5, 1.0], (40, 1)))  # powers of two are exact


def test_hdr_rle_and_flat_decode_alike(tmp_path):
    img = np.tile(hdr_test_image(), (1, 8, 1))  # 320 wide: literals and runs longer than 128
    img[5, :300] = 3.0
    write_hdr(tmp_path / "rle.hdr", img, rle=True)
    write_hdr(tmp_path / "flat.hdr", img, rle=False)
    np.testing.assert_array_equal(read_hdr(tmp_path / "rle.hdr"), read_hdr(tmp_path / "flat.hdr"))
    assert (tmp_path / "rle.hdr").stat().st_size < (tmp_path / "flat.hdr").stat().st_size


def test_hdr_hand_encoded_rle(tmp_path):
    """One 10-pixel scanline, each channel coded with runs and literals by hand."""
    width = 10
    line = bytes([2, 2, 0, width])
    line += bytes([128 + 10, 64])  # R: run of 10 x 64
    line += bytes([10]) + bytes(range(10, 20))  # G: literal of 10
    line += bytes([128 + 4, 128, 6, 1, 2, 3, 4, 5, 6])  # B: run of 4 x 128, literal of 6
    line += bytes([128 + 10, 129])  # E: exponent 129 -> scale 2**(129 - 136) = 1/128
    path = tmp_path / "hand.pic"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 10\n" + line)
    out = read_hdr(path)
    want = np.stack([np.full(10, 64), np.arange(10, 20), [128] * 4 + list(range(1, 7))], axis=-1) / 128
    np.testing.assert_array_equal(out, want[None].astype(np.float32))


def test_hdr_orientation_and_exposure(tmp_path):
    pixels = np.array([[[128, 0, 0, 129]], [[0, 128, 0, 129]]], np.uint8)  # rows as stored: red, green
    path = tmp_path / "up.hdr"
    path.write_bytes(b"#?RGBE\nEXPOSURE=2\n\n+Y 2 +X 1\n" + pixels.tobytes())
    out = read_hdr(path)  # +Y: first stored row is the bottom; EXPOSURE 2 divided out
    np.testing.assert_array_equal(out[:, 0], [[0, 0.5, 0], [0.5, 0, 0]])


def test_hdr_truncated_rle(tmp_path):
    path = tmp_path / "t.hdr"
    write_hdr(path, hdr_test_image())
    path.write_bytes(path.read_bytes()[:-30])
    with pytest.raises(ImageError, match="t.hdr: truncated"):
        read_hdr(path)


# --------------------------------------------------------------------------
# PNG
# --------------------------------------------------------------------------


def test_png8_srgb_decode(tmp_path):
    codes = np.array([[[0, 188, 255], [10, 11, 128]]], np.uint8)
    path = tmp_path / "a.png"
    Image.fromarray(codes, "RGB").save(path)
    out = read_png(path)
    assert out.dtype == np.float32 and out.shape == (1, 2, 3)
    assert out[0, 0, 0] == 0.0 and out[0, 0, 2] == 1.0
    assert out[0, 0, 1] == pytest.approx(0.5028864580325687, rel=1e-6)  # ((188/255 + 0.055)/1.055)**2.4
    assert out[0, 1, 0] == pytest.approx(10 / 255 / 12.92, rel=1e-6)  # linear segment
    assert out[0, 1, 1] == pytest.approx(((11 / 255 + 0.055) / 1.055) ** 2.4, rel=1e-6)  # just above 0.04045
    np.testing.assert_allclose(read_png(path, linear=True), codes / 255.0, rtol=1e-7)


@pytest.mark.parametrize("mode", ["L", "LA", "RGBA", "P"])
def test_png8_modes(tmp_path, mode):
    rgb = np.array([[[0, 0, 0], [255, 255, 255]], [[128, 128, 128], [64, 64, 64]]], np.uint8)
    im = Image.fromarray(rgb, "RGB")
    im = im.convert(mode) if mode != "P" else im.quantize(4)  # 4 colours: an exact palette
    path = tmp_path / f"{mode}.png"
    im.save(path)
    np.testing.assert_allclose(read_png(path, linear=True), rgb / 255.0, rtol=1e-7)


def png_filter(rows: np.ndarray, bpp: int, ftype: int) -> np.ndarray:
    """Encode byte rows (h, n) with one PNG filter type (reference, not the decoder's code)."""
    x = rows.astype(np.int64)
    left = np.zeros_like(x)
    left[:, bpp:] = x[:, :-bpp]
    up = np.zeros_like(x)
    up[1:] = x[:-1]
    ul = np.zeros_like(x)
    ul[1:, bpp:] = x[:-1, :-bpp]
    if ftype == 0:
        pred = 0
    elif ftype == 1:
        pred = left
    elif ftype == 2:
        pred = up
    elif ftype == 3:
        pred = (left + up) // 2
    else:
        p = left + up - ul
        pa, pb, pc = abs(p - left), abs(p - up), abs(p - ul)
        pred = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, ul))
    return ((x - pred) % 256).astype(np.uint8)


ADAM7 = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))


def write_png16(path, samples: np.ndarray, color_type: int, interlace: bool = False) -> None:
    """A 16-bit PNG written by hand (as a student's tracer might), cycling through all five filter types."""
    h, w, c = samples.shape
    bpp = 2 * c

    def encode(sub: np.ndarray) -> bytes:
        rows = sub.astype(">u2").reshape(sub.shape[0], -1).view(np.uint8)
        out = b""
        for y in range(rows.shape[0]):
            ftype = y % 5
            enc = png_filter(rows, bpp, ftype)[y]  # filters use the unfiltered rows above
            out += bytes([ftype]) + enc.tobytes()
        return out

    if interlace:
        raw = b"".join(encode(samples[ys::dy, xs::dx]) for xs, ys, dx, dy in ADAM7 if xs < w and ys < h)
    else:
        raw = encode(samples)

    def chunk(t: bytes, d: bytes) -> bytes:
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))

    ihdr = struct.pack(">IIBBBBB", w, h, 16, color_type, 0, 0, int(interlace))
    path.write_bytes(image_files.PNG_MAGIC + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


@pytest.mark.parametrize("color_type,channels,interlace", [(2, 3, False), (6, 4, False), (0, 1, False), (4, 2, False), (2, 3, True)])
def test_png16_keeps_16_bits(tmp_path, color_type, channels, interlace):
    samples = rng().integers(0, 65536, (11, 13, channels)).astype(np.uint16)
    samples[0, :, 0] = np.arange(30000, 30013)  # neighbours one code apart
    path = tmp_path / "s.png"
    write_png16(path, samples, color_type, interlace)
    want = samples[..., :3] if channels >= 3 else np.repeat(samples[..., :1], 3, axis=2)
    lin = read_png(path, linear=True)
    np.testing.assert_array_equal(np.round(lin.astype(np.float64) * 65535).astype(np.int64), want)
    srgb = read_png(path)
    np.testing.assert_allclose(srgb, image_files.srgb_eotf(want / 65535.0), rtol=1e-6, atol=1e-9)
    assert len(np.unique(srgb[0, :, 0])) == 13  # 8 bits would merge these


def test_png16_grey_from_pillow(tmp_path):
    """A 16-bit greyscale PNG written by pillow, an independent encoder."""
    codes = (np.arange(64, dtype=np.uint16).reshape(8, 8) * 1021 + 7).astype(np.uint16)
    path = tmp_path / "g16.png"
    Image.fromarray(codes).save(path)
    assert Image.open(path).mode.startswith("I;16")
    np.testing.assert_allclose(read_png(path, linear=True)[..., 1], codes / 65535.0, rtol=1e-7)


def test_png_corrupt(tmp_path):
    path = tmp_path / "c.png"
    Image.fromarray(np.zeros((40, 40, 3), np.uint8) + 77, "RGB").save(path)
    path.write_bytes(path.read_bytes()[:60])
    with pytest.raises(ImageError, match="c.png: truncated"):
        read_png(path)
    write_png16(path, np.zeros((4, 4, 3), np.uint16), 2)
    data = bytearray(path.read_bytes())
    data[40] ^= 0xFF  # inside the IDAT chunk: the CRC no longer matches
    path.write_bytes(bytes(data))
    with pytest.raises(ImageError, match="c.png: corrupt"):
        read_png(path)


# --------------------------------------------------------------------------
# Dispatch, previews
# --------------------------------------------------------------------------


def test_read_image_dispatch(tmp_path):
    img = gradient() / 1000.0
    write_pfm(tmp_path / "a.pfm", img)
    write_hdr(tmp_path / "a.HDR", img)
    image_files.write_png(tmp_path / "a.png", img)
    write_exr(tmp_path / "a.exr", make_result())
    for name in ("a.pfm", "a.HDR", "a.png"):
        r = read_image(tmp_path / name)
        assert (r.spp, r.variance, r.renderer) == (0, None, "unknown"), name
        assert r.mean.shape == img.shape and r.mean.dtype == np.float32
    assert read_image(tmp_path / "a.exr").spp == 1024
    np.testing.assert_array_equal(read_image(tmp_path / "a.pfm").mean, img)
    assert read_image(tmp_path / "a.png", linear_png=True).mean[0, 0, 2] == pytest.approx(tonemap(img)[0, 0, 2] / 255)


def test_png16_read_by_pypng_not_by_hand(tmp_path):
    """The hand-written 16-bit decoder is gone: pypng decodes, and a file pypng writes reads back exactly."""
    import png

    assert not hasattr(image_files, "_png_unfilter") and not hasattr(image_files, "_ADAM7")
    samples = rng().integers(0, 65536, (9, 7, 4)).astype(np.uint16)
    path = tmp_path / "p.png"
    png.from_array(samples.reshape(9, -1), "RGBA;16").save(str(path))
    lin = read_png(path, linear=True)
    np.testing.assert_array_equal(np.round(lin.astype(np.float64) * 65535).astype(np.int64), samples[..., :3])


def test_jpeg_refused_with_reason(tmp_path):
    path = tmp_path / "a.jpg"
    Image.fromarray(np.full((8, 8, 3), 128, np.uint8)).save(path, quality=95)
    with pytest.raises(ImageError, match="a.jpg: JPEG is not accepted: its lossy compression"):
        read_image(path)


@pytest.mark.parametrize("name", ["noext", "a.exr.bak", "a.webp"])
def test_unknown_extension(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(b"whatever")
    with pytest.raises(ImageError, match="unknown image type"):
        read_image(path)


def test_tonemap_known_values():
    rgb = np.array([[[0.5, 0.0, 1.0], [2.0, -1.0, np.inf], [np.nan, 0.5, 0.5], [0.001, 0.0031308, 0.2]]])
    out = tonemap(rgb)
    assert out.dtype == np.uint8 and out.shape == (1, 4, 3)
    assert out[0, 0].tolist() == [188, 0, 255]
    assert out[0, 1].tolist() == [255, 0, 255]  # clipped, not a NaN
    assert out[0, 2].tolist() == [255, 0, 255]  # NaN pixel: magenta
    assert out[0, 3].tolist() == [3, 10, 124]  # 12.92 x below 0.0031308; 1.055 x^(1/2.4) - 0.055 above
    assert tonemap(np.full((1, 1, 3), 1.0), exposure=-1.0)[0, 0].tolist() == [188] * 3


def test_srgb_curve_both_ways_and_its_slope():
    x = np.concatenate([np.linspace(0.0, 0.01, 101), np.linspace(0.01, 1.0, 1001)])
    np.testing.assert_allclose(image_files.srgb_eotf(image_files.srgb_oetf(x)), x, rtol=1e-12, atol=1e-15)
    assert image_files.srgb_oetf(0.5) == pytest.approx(1.055 * 0.5 ** (1 / 2.4) - 0.055)
    assert image_files.srgb_eotf(0.04) == pytest.approx(0.04 / 12.92) and image_files.srgb_eotf(1.0) == pytest.approx(1.0)
    v, h = np.linspace(0.001, 0.999, 500), 1e-6
    numeric = (image_files.srgb_eotf(v + h) - image_files.srgb_eotf(v - h)) / (2 * h)
    np.testing.assert_allclose(image_files.srgb_eotf_slope(v), numeric, rtol=1e-4)
    with np.errstate(all="raise"):  # negative and NaN inputs: the linear segment, NaN; never a warning
        out = image_files.srgb_eotf(np.array([-0.5, np.nan])), image_files.srgb_oetf(np.array([-0.5, np.nan]))
    assert out[0][0] == pytest.approx(-0.5 / 12.92) and out[1][0] == pytest.approx(-0.5 * 12.92)
    assert np.isnan(out[0][1]) and np.isnan(out[1][1])


def test_write_png_preview(tmp_path):
    img = gradient() / 600.0
    img[1, 1, 0] = np.nan
    path = tmp_path / "p.png"
    image_files.write_png(path, img, exposure=1.0)
    np.testing.assert_array_equal(np.asarray(Image.open(path)), tonemap(img, 1.0))
    assert tuple(np.asarray(Image.open(path))[1, 1]) == (255, 0, 255)
    assert os.listdir(tmp_path) == ["p.png"]


def test_side_by_side(tmp_path):
    a, b = gradient() / 600.0, np.full((4, 3, 3), 0.5, np.float32)
    path = tmp_path / "strip.png"
    image_files.side_by_side(path, [a, b], ["mcrt", "mitsuba"])
    strip = np.asarray(Image.open(path).convert("RGB"))
    assert strip.shape[0] > a.shape[0] and strip.shape[1] >= a.shape[1] + b.shape[1]
    top = strip[: strip.shape[0] - a.shape[0]]
    assert (top > 128).any()  # the labels were drawn
    rows = strip[strip.shape[0] - a.shape[0]:]
    tile = tonemap(a)
    # the first image appears unchanged somewhere in the bottom rows
    found = any(np.array_equal(rows[:, x: x + tile.shape[1]], tile) for x in range(rows.shape[1] - tile.shape[1] + 1))
    assert found
    with pytest.raises(ValueError, match="one label per image"):
        image_files.side_by_side(path, [a, b], ["only one"])
