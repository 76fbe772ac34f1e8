"""Input that would take the machine down or crash a command (issue 29, items 2 and 6).

* every image reader reads the image's dimensions before decoding it and refuses more than
  :data:`mcrt.image_files.MAX_PIXELS` pixels (a 280 KB 16-bit PNG of 12000 x 12000 took ``mcrt check`` to 5.5 GB);
* scene and assignment files are read to a size cap, and only when regular files (``--scene /dev/zero``);
* a flat tetrahedron is refused when the scene is loaded, not by a traceback of ``mcrt render``;
* ``--exposure nan`` / ``inf`` are refused by the command line.
"""

from __future__ import annotations

import os
import resource
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from mcrt import image_files
from mcrt.grade.assignment import AssignmentError, load_assignment
from mcrt.image_files import ImageError, read_image
from mcrt.scene import CANONICAL, SceneError, load_scene

W, H = 12000, 12000  # the size of the PNG: 144 million pixels


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def big_png(path: Path, bits: int, w: int = W, h: int = H) -> Path:
    """A valid PNG of w x h black RGB pixels (a few hundred KB: zeros compress well), written row by row."""
    row = b"\0" + bytes(w * 3 * bits // 8)
    z = zlib.compressobj(9)
    idat = b"".join(z.compress(row) for _ in range(h)) + z.flush()
    ihdr = struct.pack(">IIBBBBB", w, h, bits, 2, 0, 0, 0)
    path.write_bytes(image_files.PNG_MAGIC + _png_chunk(b"IHDR", ihdr) + _png_chunk(b"IDAT", idat) + _png_chunk(b"IEND", b""))
    return path


def test_a_16bit_png_of_12000x12000_is_refused_before_decoding(tmp_path):
    p = big_png(tmp_path / "bomb.png", 16)
    assert p.stat().st_size < 1_000_000  # the was 280 KB
    # In a child with an address-space limit far below what decoding would take (12000^2 x 3 x 2 bytes and more).
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (1536 << 20, 1536 << 20)); import mcrt.image_files as m\n"
            "try: m.read_image(sys.argv[1])\nexcept m.ImageError as e: print(e); sys.exit(3)\n")
    r = subprocess.run([sys.executable, "-c", code, str(p)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 3, r.stderr[-2000:]
    assert f"{W}x{H} pixels is more than" in r.stdout


@pytest.mark.parametrize("bits", [8, 16])
def test_png_over_the_cap_is_refused_with_its_size(tmp_path, bits):
    p = big_png(tmp_path / "big.png", bits, w=4097, h=4096)
    with pytest.raises(ImageError, match=r"big\.png: 4097x4096 pixels is more than the 16,777,216 pixels"):
        read_image(p)


def test_png_at_the_cap_is_read(tmp_path):
    p = big_png(tmp_path / "ok.png", 8, w=2048, h=8)
    assert read_image(p).mean.shape == (8, 2048, 3)


def _header_only(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def test_pfm_hdr_ppm_declaring_too_many_pixels_are_refused_before_reading_the_raster(tmp_path):
    # Each file declares 12000 x 12000 and holds a little data: without the cap the message would be "truncated".
    files = {
        "a.pfm": b"PF\n12000 12000\n-1.0\n" + bytes(4096),
        "a.hdr": b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 12000 +X 12000\n" + bytes(4096),
        "a.ppm": b"P6\n12000 12000\n255\n" + bytes(4096),
        "b.ppm": b"P6\n12000 12000\n65535\n" + bytes(4096),
    }
    for name, data in files.items():
        with pytest.raises(ImageError, match=rf"{name}: 12000x12000 pixels is more than"):
            read_image(_header_only(tmp_path / name, data))


@pytest.mark.parametrize("w, h", [(5000, 4000), (20000, 20000)])  # the second is past Pillow's own limit too
def test_bmp_tga_ppm_declaring_too_many_pixels_are_refused(tmp_path, w, h):
    bmp = (b"BM" + struct.pack("<IHHI", 54 + 16, 0, 0, 54) + struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, 0, 2835, 2835, 0, 0)
           + bytes(16))
    tga = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 24, 0) + bytes(16)
    ppm = f"P6\n{w} {h}\n255\n".encode() + bytes(16)
    for name, data in (("c.bmp", bmp), ("c.tga", tga), ("c.ppm", ppm)):
        with pytest.raises(ImageError, match=rf"{name}: (more than the 16,777,216|{w}x{h}) pixels"):
            read_image(_header_only(tmp_path / name, data))


def test_exr_declaring_too_many_pixels_is_refused_from_its_header(tmp_path):
    p = tmp_path / "small.exr"
    ch = {c: np.zeros((4, 4), np.float32) for c in "RGB"}
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}, ch).write(str(p))
    data = bytearray(p.read_bytes())
    # The header's dataWindow (box2i: xMin, yMin, xMax, yMax) grows to 12000 x 12000; the pixels stay 4 x 4.
    key = b"dataWindow\0box2i\0" + struct.pack("<i", 16)
    at = data.index(key) + len(key)
    data[at:at + 16] = struct.pack("<iiii", 0, 0, W - 1, H - 1)
    p.write_bytes(bytes(data))
    with pytest.raises(ImageError, match=rf"small\.exr: {W}x{H} pixels is more than"):
        read_image(p)


# -- scene and assignment files -------------------------------------------------


def test_scene_from_dev_zero_is_refused_at_once():
    with pytest.raises(SceneError, match=r"^/dev/zero: not a regular file"):
        load_scene("/dev/zero")


def test_a_scene_file_over_the_size_cap_is_refused(tmp_path):
    p = tmp_path / "big.toml"
    p.write_bytes(CANONICAL.read_bytes() + b"#" * (1 << 20))
    with pytest.raises(SceneError, match=r"big\.toml: larger than 1024 KiB"):
        load_scene(p)


def test_a_fifo_scene_does_not_hang(tmp_path):
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    with pytest.raises(SceneError, match=r"scene\.toml: not a regular file"):
        load_scene(fifo)


def test_assignment_from_dev_zero_or_too_large_is_refused(tmp_path):
    with pytest.raises(AssignmentError, match=r"^/dev/zero: not a regular file"):
        load_assignment("/dev/zero")
    p = tmp_path / "a.toml"
    p.write_bytes(b"#" * ((1 << 20) + 1))
    with pytest.raises(AssignmentError, match=r"a\.toml: larger than 1024 KiB"):
        load_assignment(p)
    with pytest.raises(AssignmentError, match=r"missing\.toml: no such file"):
        load_assignment(tmp_path / "missing.toml")


def test_cli_scene_dev_zero_is_one_line_and_exit_2():
    r = subprocess.run([sys.executable, "-m", "mcrt.cli", "scene", "/dev/zero"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == ["mcrt: /dev/zero: not a regular file (a scene file must be one)"]


def flat_scene(tmp_path) -> Path:
    text = CANONICAL.read_text()
    old = "[8.5, -2.3, -2.0]]"  # the apex of the canonical tetrahedron, moved down into its base's plane
    assert old in text
    p = tmp_path / "flat.toml"
    p.write_text(text.replace(old, "[8.5, -2.3, -4.9]]"))
    return p


def test_a_flat_tetrahedron_is_refused_at_load(tmp_path):
    with pytest.raises(SceneError, match=r"flat\.toml: objects\[0\]\.vertices: flat tetrahedron"):
        load_scene(flat_scene(tmp_path))


def test_render_of_a_flat_tetrahedron_is_a_one_line_error(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mcrt.cli", "render", "--scene", str(flat_scene(tmp_path)), "--res", "8", "--spp", "1",
                        "-o", str(tmp_path / "o.exr")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr[-2000:]
    assert "Traceback" not in r.stderr
    assert r.stderr.strip().splitlines()[-1].endswith("flat tetrahedron: the four vertices lie in one plane (zero volume)")


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "NaN"])
def test_exposure_must_be_finite(value, tmp_path):
    r = subprocess.run([sys.executable, "-m", "mcrt.cli", "render", f"--exposure={value}", "--res", "8", "--spp", "1",
                        "-o", str(tmp_path / "o.exr")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2
    assert f"argument --exposure: must be a finite number, got '{value}'" in r.stderr
    assert not (tmp_path / "o.exr").exists()


# -- code mode: what comes back, what goes in ---------------------------------


def test_a_result_nested_200000_deep_is_malformed_not_a_grader_crash():
    from mcrt.grade.codemode import _parse_results

    body = b"[" * 200_000 + b"]" * 200_000
    assert _parse_results(body + struct.pack("<Q", len(body))) is None


def test_the_graded_module_is_copied_before_the_file_budget_runs_out(tmp_path):
    from mcrt.grade.codemode import copy_submission

    src = tmp_path / "student"
    src.mkdir()
    for k in range(20):
        (src / f"a{k:02d}.txt").write_text("filler")
    (src / "tracer.py").write_text("def render(): pass\n")
    notes = copy_submission(src, tmp_path / "copy", max_files=5, first="tracer.py")
    assert (tmp_path / "copy" / "tracer.py").read_text() == "def render(): pass\n"
    assert len(list((tmp_path / "copy").iterdir())) == 5
    assert any("more than 5 files" in n for n in notes)
