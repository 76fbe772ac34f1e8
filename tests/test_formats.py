"""The formats students hand in (issue 18, point 3), and ``mcrt check`` on the course's 800 x 800 renders.

Test files are written the way other programs write them: netpbm by hand
with NumPy (as a student's tracer does), PNG with Pillow and pypng, BMP and
TGA with Pillow and, where it is installed, ImageMagick's ``convert`` -
never with mcrt's own writers. The 800 x 800 render is made once per session
with ``mcrt render --preset course2023`` (at 32 spp, above the assignment's
min_spp of 16) and graded through ``mcrt check`` with the packaged
assignment; its references and catalogue are cached for the session (or in
``$MCRT_CACHE`` when set). Those checks prepare the assignment from nothing, which takes minutes: they are
``long`` (run with ``MCRT_SLOW=1``, as ``.ci/run`` does; tests/conftest.py).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mcrt import image_files
from mcrt.grade.assignment import load_assignment
from mcrt.grade.submissions import choose_images, discover, read_manifest
from mcrt.image_files import ImageError, read_image, srgb_eotf
from mcrt.scene import DATA_DIR

ROOT = Path(__file__).resolve().parent.parent


def rng():
    return np.random.default_rng(18)


def codes8(h=6, w=5):
    c = rng().integers(0, 256, (h, w, 3)).astype(np.uint8)
    c[0, 0] = (0, 128, 255)
    return c


def codes16(h=6, w=5):
    c = rng().integers(0, 65536, (h, w, 3)).astype(np.uint16)
    c[0, :3, 0] = (30000, 30001, 30002)  # one code apart: 8 bits would merge them
    return c


def write_p6(path, codes, maxval):
    """A binary PPM as a student tracer writes it: header, then big-endian samples."""
    h, w, _ = codes.shape
    raster = codes.astype(">u2" if maxval > 255 else np.uint8).tobytes()
    path.write_bytes(f"P6\n# written by my ray tracer\n{w} {h}\n{maxval}\n".encode() + raster)


def write_p3(path, codes, maxval):
    """A plain (ASCII) PPM: one row of samples per line, the classic fprintf loop."""
    h, w, _ = codes.shape
    rows = "\n".join(" ".join(str(int(v)) for v in codes[y].ravel()) for y in range(h))
    path.write_text(f"P3\n{w} {h}\n# a comment\n{maxval}\n{rows}\n")


# --------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------


@pytest.mark.parametrize("writer", [write_p6, write_p3])
@pytest.mark.parametrize("bits", [8, 16])
def test_ppm_p3_p6_8_and_16_bit(tmp_path, writer, bits):
    c = codes8() if bits == 8 else codes16()
    maxval = 255 if bits == 8 else 65535
    path = tmp_path / "render.ppm"
    writer(path, c, maxval)
    r = read_image(path, linear_png=True)
    assert r.extra == {"file.format": "PPM", "file.bits": str(bits)}
    np.testing.assert_array_equal(np.round(r.mean.astype(np.float64) * maxval).astype(np.int64), c)
    np.testing.assert_allclose(read_image(path).mean, srgb_eotf(c / maxval), rtol=1e-6, atol=1e-9)


def test_ppm_other_maxval_and_pgm(tmp_path):
    c = (codes16() % 1024).astype(np.uint16)
    write_p6(tmp_path / "a.ppm", c, 1023)
    np.testing.assert_allclose(read_image(tmp_path / "a.ppm", linear_png=True).mean, c / 1023, rtol=1e-6)
    grey = codes16()[..., 0]
    (tmp_path / "g.pgm").write_bytes(b"P5\n5 6\n65535\n" + grey.astype(">u2").tobytes())
    r = read_image(tmp_path / "g.pgm", linear_png=True)
    np.testing.assert_allclose(r.mean[..., 2] * 65535, grey, atol=1e-2)


def test_ppm_truncated_and_garbage(tmp_path):
    path = tmp_path / "t.ppm"
    write_p6(path, codes16(), 65535)
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(ImageError, match="t.ppm: truncated"):
        read_image(path)
    write_p6(path, codes8(), 255)
    path.write_bytes(path.read_bytes()[:-10])
    with pytest.raises(ImageError, match="t.ppm: truncated or corrupt"):
        read_image(path)
    path.write_bytes(b"hello world")
    with pytest.raises(ImageError, match="t.ppm: not a netpbm"):
        read_image(path)


@pytest.mark.parametrize("ext", ["bmp", "tga"])
def test_bmp_tga_by_pillow(tmp_path, ext):
    c = codes8()
    path = tmp_path / f"render.{ext}"
    Image.fromarray(c).save(path)
    r = read_image(path, linear_png=True)
    assert r.extra["file.format"] == ext.upper()
    np.testing.assert_array_equal(np.round(r.mean * 255).astype(np.uint8), c)
    Image.fromarray(np.dstack([c, np.full(c.shape[:2], 7, np.uint8)]), "RGBA").save(path)  # alpha dropped
    np.testing.assert_array_equal(np.round(read_image(path, linear_png=True).mean * 255).astype(np.uint8), c)


def has_imagemagick() -> bool:
    if shutil.which("convert") is None:
        return False
    try:
        out = subprocess.run(["convert", "-version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return False
    return out.returncode == 0 and "ImageMagick" in out.stdout


@pytest.mark.skipif(not has_imagemagick(), reason="ImageMagick's convert is not installed (apt-get install imagemagick)")
@pytest.mark.parametrize("target", ["out.bmp", "out.tga", "out.png", "out16.png", "out.ppm", "out16.ppm"])
def test_files_written_by_imagemagick(tmp_path, target):
    c = codes16() if "16" in target else codes8()
    src = tmp_path / "src.ppm"
    write_p6(src, c, 65535 if "16" in target else 255)
    out = tmp_path / target
    depth = ["-depth", "16"] if "16" in target else ["-depth", "8"]
    extra = ["-compress", "none"] if target == "out.ppm" else []  # a plain P3 file
    if target.endswith(".tga"):
        # ImageMagick 6 writes the top row first but, unless told its orientation, flags the file as
        # bottom-up; Pillow follows the flag (TGA's specification), so the file would read upside down.
        extra = ["-type", "TrueColor", "-orient", "TopLeft"]
    subprocess.run(["convert", str(src), *depth, *extra, str(out)], check=True, capture_output=True, timeout=60)
    maxval = 65535 if "16" in target else 255
    r = read_image(out, linear_png=True)
    np.testing.assert_array_equal(np.round(r.mean.astype(np.float64) * maxval).astype(np.int64), c)


def test_png16_by_pypng(tmp_path):
    import png

    c = codes16()
    path = tmp_path / "a.png"
    png.from_array(c.reshape(c.shape[0], -1), "RGB;16").save(str(path))
    r = read_image(path, linear_png=True)
    assert r.extra == {"file.format": "PNG", "file.bits": "16"}
    np.testing.assert_array_equal(np.round(r.mean.astype(np.float64) * 65535).astype(np.int64), c)
    w = png.Writer(c.shape[1], c.shape[0], greyscale=True, bitdepth=16, interlace=True)
    with open(path, "wb") as f:
        w.write(f, c[..., 0])
    np.testing.assert_array_equal(np.round(read_image(path, linear_png=True).mean[..., 1] * 65535), c[..., 0])


def test_jpeg_refused_with_its_reason(tmp_path):
    Image.fromarray(codes8()).save(tmp_path / "alice.jpg", quality=95)
    with pytest.raises(ImageError, match="JPEG is not accepted: its lossy compression"):
        read_image(tmp_path / "alice.jpg")
    (sub,) = discover(tmp_path)
    assert "JPEG is not accepted" in sub.problem and sub.images == []
    # next to a real render the JPEG is a preview: noted, not graded
    folder = tmp_path / "bob"
    folder.mkdir()
    Image.fromarray(codes8()).save(folder / "preview.jpg")
    write_p6(folder / "render.ppm", codes8(), 255)
    (b,) = discover(folder, single=True)
    assert b.problem is None and [Path(i).name for i in b.images] == ["render.ppm"]
    assert any("JPEG files are not graded" in n for n in b.notes)


def test_discovery_knows_the_new_formats(tmp_path):
    for name in ("a.ppm", "b.bmp", "c.tga"):
        Image.fromarray(codes8()).save(tmp_path / name)
    subs = discover(tmp_path)
    assert [s.student for s in subs] == ["a", "b", "c"] and all(s.problem is None for s in subs)
    # an 8-bit file beside an HDR render is a preview
    d = tmp_path / "dave"
    d.mkdir()
    (d / "r.pfm").write_bytes(b"PF\n1 1\n-1.0\n" + np.zeros(3, "<f4").tobytes())
    write_p6(d / "r.ppm", codes8(1, 1), 255)
    (s,) = discover(d, single=True)
    images, notes = choose_images(s, read_manifest(None))
    assert [Path(i).name for i in images] == ["r.pfm"] and "previews" in notes[0]


# --------------------------------------------------------------------------
# The 800 x 800 assignment and mcrt check
# --------------------------------------------------------------------------


def test_800_assignment_ships_with_the_package():
    from mcrt.grade.cli import DEFAULT_CHECK_ASSIGNMENT, resolve_assignment

    path = DATA_DIR / "assignments" / f"{DEFAULT_CHECK_ASSIGNMENT}.toml"
    assert resolve_assignment(DEFAULT_CHECK_ASSIGNMENT) == path
    a = load_assignment(path)
    assert (a.width, a.height, a.grade_width, a.grade_height, a.factor) == (800, 800, 100, 100, 8)
    assert a.min_spp <= 32 and a.max_score == 100
    course = load_assignment(resolve_assignment("course2023"))
    assert [c.points for c in a.rubric] == [c.points for c in course.rubric]
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert "*.toml" in globs["mcrt.data.assignments"]
    deps = " ".join(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"])
    assert "pypng" in deps


def test_check_help_shows_every_default(capsys):
    from mcrt.grade.cli import DEFAULT_CHECK_ASSIGNMENT, build_parser

    with pytest.raises(SystemExit):
        build_parser().parse_args(["check", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for opt in ("--assignment", "--out", "--cache", "--quiet"):
        assert opt in text
    assert text.count("(default:") >= 4 and f"default: {DEFAULT_CHECK_ASSIGNMENT}" in text


def test_check_unusable_input(tmp_path, capsys):
    from mcrt.grade.cli import main

    assert main(["check", str(tmp_path / "missing.ppm")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["check", str(tmp_path)]) == 2
    assert main(["check", str(tmp_path / "x.ppm"), "--assignment", str(tmp_path / "nope.toml")]) == 2


@pytest.fixture(scope="session")
def render800(tmp_path_factory):
    """A correct 800 x 800 render from ``mcrt render --preset course2023`` (32 spp), linear RGB."""
    from mcrt.cli import main

    d = tmp_path_factory.mktemp("r800")
    assert main(["render", "--preset", "course2023", "--spp", "32", "--seed", "18", "-o", str(d / "r.exr")]) == 0
    import OpenEXR

    ch = OpenEXR.File(str(d / "r.exr")).channels()
    rgb = ch["RGB"].pixels if "RGB" in ch else np.stack([ch[c].pixels for c in "RGB"], axis=-1)
    assert rgb.shape == (800, 800, 3)
    return np.asarray(rgb, np.float64)


def _srgb8(rgb):
    x = np.clip(rgb, 0.0, 1.0)
    v = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.floor(v * 255 + 0.5).astype(np.uint8)


@pytest.mark.slow
@pytest.mark.long
@pytest.mark.parametrize("kind", ["ppm", "png"])
def test_check_gives_a_correct_800_render_full_marks(tmp_path, render800, grade_cache, kind, capsys):
    from mcrt.grade.cli import main

    b = _srgb8(render800)
    path = tmp_path / f"my_render.{kind}"
    if kind == "ppm":
        write_p6(path, b, 255)  # what a student's tracer writes
    else:
        Image.fromarray(b, "RGB").save(path)  # gamma-encoded (sRGB) 8-bit PNG
    rc = main(["check", str(path), "--cache", str(grade_cache), "--out", str(tmp_path / "fb"), "-q"])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert out.startswith(f"my_render.{kind}: 100 / 100 points") and "800x800 as asked" in out
    res = json.loads((tmp_path / "fb" / "my_render" / "results.json").read_text())
    assert res["score"] == res["max_score"] == 100


@pytest.mark.slow
@pytest.mark.long
def test_check_reports_a_wrong_800_render(tmp_path, render800, grade_cache, capsys):
    """Exit 1 and the reason: the same render upside down (flipped back and graded: only those points lost)."""
    from mcrt.grade.cli import main

    path = tmp_path / "flipped.ppm"
    write_p6(path, _srgb8(render800)[::-1], 255)
    rc = main(["check", str(path), "--cache", str(grade_cache), "-q"])
    out = capsys.readouterr().out
    assert rc == 1 and "upside down" in out and "95 / 100" in out
