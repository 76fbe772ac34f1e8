"""Image mode and scene files under hostile or careless input (issue 18, point 5).

Each case of the issue gets its own one-line message and its results.json,
and the class outputs (grades.csv, summary.md, summary.json) are always
written, whatever the bytes of names and messages:

* file names (and so messages) that are not valid UTF-8;
* symbolic links (a link to the committed reference must not score), FIFOs,
  broken links and links to devices, at the top of the class folder and
  inside a student's folder;
* a 5000-deep array in manifest.toml; an EXR header ``spp = -5``;
* scene files: wrong types, non-UTF-8 or deeply nested files, values whose
  render would overflow float32, absurd resolutions and sample counts;
* a reference build killed between writing the EXR and the manifest.
"""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from mcrt.grade import checks as ck
from mcrt.grade.assignment import assignment_from_dict
from mcrt.grade.batch import grade_class
from mcrt.grade.expected import prepare_context
from mcrt.grade.submissions import discover, read_manifest
from mcrt.image_files import write_exr
from mcrt.render import render
from mcrt.scene import CANONICAL, DATA_DIR, SceneError, load_scene

RES = 32
#: A 32x32 assignment with cheap catalogue renders (the bias test is not what is tested here).
ASSIGNMENT = {"name": "robust32", "scene": {"camera": "near", "width": RES, "height": RES, "spp": 64, "min_spp": 16},
              "grading": {"tiles": [8, 16, 0], "diagnosis_spp": 1024, "reference_spp": 1024}}
BAD = b"caf\xe9"  # Latin-1, not UTF-8


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("robust")


@pytest.fixture(scope="module")
def context(workdir, grade_cache):
    return prepare_context(assignment_from_dict(ASSIGNMENT, "robust32.toml", base=workdir), grade_cache)


@pytest.fixture(scope="module")
def good(workdir):
    """A correct 32x32 render at 64 spp."""
    scene = load_scene()
    r = render(scene, scene.settings(camera="near", width=RES, height=RES, spp=64, max_depth=8), seed=1818, progress=False)
    path = workdir / "good.exr"
    write_exr(path, r)
    return path


def _committed_reference() -> Path:
    return DATA_DIR / "canonical_near_64x64_d8.exr"


@pytest.fixture(scope="module")
def graded(workdir, context, good):
    """A class of hostile hand-ins, graded once by two workers."""
    d = workdir / "class"
    d.mkdir()
    (d / "ok.exr").write_bytes(good.read_bytes())
    os.symlink(_committed_reference(), d / "mallory.exr")  # the committed reference: must not score
    os.symlink(d / "missing.exr", d / "broken.exr")
    os.symlink("/dev/zero", d / "device.exr")
    os.mkfifo(d / "pipe.exr")
    # a student folder with a good render, a FIFO and a link to another student's file
    s = d / "sam"
    s.mkdir()
    (s / "render.exr").write_bytes(good.read_bytes())
    os.mkfifo(s / "capture.exr")
    os.symlink(d / "ok.exr", s / "other.exr")
    # a folder that is a link (to the references)
    os.symlink(DATA_DIR, d / "linkdir")
    # names that are not UTF-8: a good render and a garbage file (its message holds the name)
    root = os.fsencode(d)
    with open(os.path.join(root, BAD + b"_good.exr"), "wb") as f:
        f.write(good.read_bytes())
    with open(os.path.join(root, BAD + b"_bad.exr"), "wb") as f:
        f.write(b"not an image \xff\xfe")
    bad_dir = os.path.join(root, BAD + b"_dir")
    os.mkdir(bad_dir)
    with open(os.path.join(bad_dir, BAD + b".png"), "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n garbage")
    # a correct render whose manifest holds a 5000-deep array
    deep = d / "deep"
    deep.mkdir()
    (deep / "render.exr").write_bytes(good.read_bytes())
    (deep / "manifest.toml").write_text("spp = 64\nnotes = " + "[" * 5000 + "]" * 5000 + "\n")
    out = workdir / "out"
    res = grade_class(d, context.assignment, out, jobs=2, context=context, log=None)
    by = {r.student: r for r in res.results}
    return out, res, by


def _results(out: Path, student: str) -> dict:
    return json.loads((out / student / "results.json").read_text(encoding="utf-8"))


def _all_text(r) -> str:
    return " ".join([r.summary, *r.notes, *(t.output for t in r.tests)])


def test_class_outputs_always_written(graded):
    out, res, by = graded
    for name in ("grades.csv", "summary.md", "summary.json"):
        assert (out / name).is_file(), name
        (out / name).read_text(encoding="utf-8")  # valid UTF-8
    assert not [p.name for p in out.rglob("*.tmp")]
    rows = list(csv.DictReader((out / "grades.csv").open(encoding="utf-8")))
    assert len(rows) == len(res.results)
    for r in res.results:  # one results.json per entry found, valid UTF-8 JSON
        data = _results(out, r.student)
        json.dumps(data, ensure_ascii=False).encode("utf-8")


def test_non_utf8_names_and_messages(graded):
    out, _, by = graded
    ok = [s for s in by if s.endswith("_good")]
    assert ok and by[ok[0]].score == by[ok[0]].max_score
    (bad,) = [s for s in by if s.endswith("_bad")]
    data = _results(out, bad)
    assert data["score"] == 0
    text = json.dumps(data, ensure_ascii=False)
    assert "\ufffd" in text and "\\udc" not in text  # the bad byte is shown as U+FFFD, never a lone surrogate
    (folder,) = [s for s in by if s.endswith("_dir")]
    assert by[folder].score == 0 and "png" in _all_text(by[folder]).lower()


def test_symlink_to_the_reference_does_not_score(graded):
    out, _, by = graded
    r = by["mallory"]
    assert r.score == 0 and "symbolic link" in _all_text(r)
    assert _results(out, "mallory")["score"] == 0


@pytest.mark.parametrize("student,word", [("broken", "broken symbolic link"), ("device", "a device"),
                                          ("pipe", "FIFO"), ("linkdir", "symbolic link (to a folder)")])
def test_special_files_are_reported(graded, student, word):
    out, _, by = graded
    r = by[student]
    assert r.score == 0 and word in _all_text(r)
    assert (out / student / "results.json").is_file()
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert student in summary


def test_special_files_inside_a_folder_are_noted(graded):
    _, _, by = graded
    r = by["sam"]
    assert r.score == r.max_score  # the regular render is graded alone
    notes = " ".join(r.notes)
    assert "capture.exr is a FIFO" in notes and "other.exr is a symbolic link" in notes


def test_deep_manifest_does_not_crash_a_correct_render(graded, tmp_path):
    _, _, by = graded
    r = by["deep"]
    assert r.score == r.max_score
    assert any("nested too deeply" in n for n in r.notes)
    p = tmp_path / "m.json"
    p.write_text('{"spp": 4, "images": ' + "[" * 5000 + "]" * 5000 + "}")
    m = read_manifest(str(p))
    assert m.spp is None and "nested too deeply" in m.warnings[0]


def test_discovery_never_opens_a_fifo(tmp_path):
    os.mkfifo(tmp_path / "x.toml")
    os.mkfifo(tmp_path / "y.exr")
    subs = discover(tmp_path)  # would block forever if it opened one
    assert {s.student for s in subs} == {"x", "y"} and all("FIFO" in s.problem for s in subs)
    m = read_manifest(str(tmp_path / "x.toml"))
    assert "FIFO" in m.warnings[0]


def test_exr_header_negative_spp_rejected_like_the_manifest(tmp_path, good):
    from mcrt.image_files import read_exr

    r = read_exr(good)
    ch = {c: np.ascontiguousarray(r.mean[..., i]) for i, c in enumerate("RGB")}
    path = tmp_path / "neg.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "spp": -5}, ch).write(str(path))
    loaded, err = ck.read_renders([str(path)], False)
    assert err is None and loaded.spp_file is None
    assert any("spp attribute must be a positive integer, got -5; ignored" in n for n in loaded.notes)
    (tmp_path / "neg.toml").write_text("spp = -5\n")
    assert "spp must be a positive integer, got -5; ignored" in read_manifest(str(tmp_path / "neg.toml")).warnings[0]


# --------------------------------------------------------------------------
# Scene files
# --------------------------------------------------------------------------


def _scene_with(tmp_path, old: str, new: str, name="s.toml") -> Path:
    text = CANONICAL.read_text()
    assert old in text
    p = tmp_path / name
    p.write_text(text.replace(old, new, 1))
    return p


@pytest.mark.parametrize("old,new,match", [
    ("radiance = [20.0, 20.0, 20.0]", "radiance = [1e308, 20.0, 20.0]", r"light.radiance\[0\]: 1e\+308 is beyond 4e\+08"),
    ("radiance = [20.0, 20.0, 20.0]", "radiance = [20.0, 1e9, 20.0]", r"light.radiance\[1\]: 1e\+09 is beyond"),
    ("[presets.course2023]", "[presets.course2023]\ncamera = 5", r"presets.course2023.camera: must be a camera's name, got 5"),
    ("[presets.course2023]", "[presets.huge]\nspp = 9223372036854775807\n[presets.course2023]", r"presets.huge.spp: must be at most 2147483647"),
    ("[presets.course2023]", "[presets.course2023]\ncamera = \"side\"", r"presets.course2023.camera: no camera named 'side'"),
])
def test_scene_values_refused_at_load_time(tmp_path, old, new, match):
    with pytest.raises(SceneError, match=match):
        load_scene(_scene_with(tmp_path, old, new))


def test_scene_render_camera_of_wrong_type(tmp_path):
    text = CANONICAL.read_text().replace('[render]\ncamera = "near"', "[render]\ncamera = [1]", 1)
    assert "camera = [1]" in text
    (tmp_path / "c.toml").write_text(text)
    with pytest.raises(SceneError, match=r"c.toml: render.camera: must be a camera's name, got \[1\]"):
        load_scene(tmp_path / "c.toml")


def test_scene_coordinates_beyond_float32(tmp_path):
    import re

    from mcrt.scene import COORD_MAX, RADIANCE_MAX

    text = CANONICAL.read_text()

    m = re.search(r"eye = \[([^\]]*)\]", text)
    p = tmp_path / "far.toml"
    p.write_text(text.replace(m.group(0), "eye = [1e20, 0.0, 1.0]", 1))
    with pytest.raises(SceneError, match=r"cameras.near.eye\[0\]: 1e\+20 is beyond \+-5.3e\+15, the largest value"):
        load_scene(p)
    assert 1e6 < COORD_MAX < 1e19 and 20 < RADIANCE_MAX < 1e12


def test_scene_file_not_utf8_or_too_deep(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes(CANONICAL.read_bytes().replace(b"# ", b"# \xe9 ", 1))
    with pytest.raises(SceneError, match=r"latin1.toml: not valid UTF-8 \(byte 0xe9 on line \d+\)"):
        load_scene(p)
    p = tmp_path / "deep.toml"
    p.write_text(CANONICAL.read_text() + "\n[extra]\nx = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(SceneError, match="deep.toml: not valid TOML: arrays or tables nested too deeply"):
        load_scene(p)


def test_absurd_settings_have_a_message(capsys):
    scene = load_scene()
    with pytest.raises(SceneError, match=r"render.width: must be at most 16384 .*got 100000"):
        scene.settings(width=100000)
    with pytest.raises(SceneError, match=r"render.spp: must be at most 2147483647"):
        scene.settings(spp=2**63 - 1)
    from mcrt.cli import main

    assert main(["render", "--res", "100000", "-o", "/nonexistent/x.exr"]) == 2
    err = capsys.readouterr().err.strip()
    assert "width: must be at most 16384" in err and len(err.splitlines()) == 1


# --------------------------------------------------------------------------
# A reference and its manifest: together or not at all
# --------------------------------------------------------------------------


def _pair(tmp_path):
    from mcrt.groundtruth import manifest as mf

    d = tmp_path / "ref"
    d.mkdir()
    (d / "k.exr").write_bytes(b"old reference")
    mf.write_manifest(d, {"references": {"k": {"file": "k.exr", "sha256": mf.sha256_file(d / "k.exr"), "spp": 1}}})
    staged = d / f".k.exr.{os.getpid()}.abcd0123.tmp"
    staged.write_bytes(b"new reference")
    entry = {"file": "k.exr", "sha256": mf.sha256_file(staged), "spp": 2}
    return mf, d, staged, entry


def _consistent(mf, d) -> int:
    e = mf.read_manifest(d)["references"]["k"]
    assert mf.sha256_file(d / e["file"]) == e["sha256"]
    return e["spp"]


def test_commit_crash_after_the_rename_keeps_the_new_pair(tmp_path, monkeypatch):
    mf, d, staged, entry = _pair(tmp_path)

    def killed(*a, **k):
        raise KeyboardInterrupt("killed between the EXR and the manifest")

    monkeypatch.setattr(mf, "write_manifest", killed)
    with pytest.raises(KeyboardInterrupt):
        mf.commit_reference(d, staged, "k", entry)
    monkeypatch.undo()
    assert (d / "k.exr").read_bytes() == b"new reference"
    assert _consistent(mf, d) == 2  # the journal describes the file on disk
    with mf.manifest_lock(d):
        mf.recover_pending(d)
    assert not (d / mf.PENDING_NAME).exists() and _consistent(mf, d) == 2
    assert json.loads((d / "manifest.json").read_text())["references"]["k"]["spp"] == 2


def test_commit_crash_before_the_rename_keeps_the_old_pair(tmp_path, monkeypatch):
    mf, d, staged, entry = _pair(tmp_path)
    journal_seen = []

    def killed(src, dst):
        journal_seen.append((d / mf.PENDING_NAME).exists())
        raise OSError("disk full")

    monkeypatch.setattr(mf, "_replace_file", killed)
    with pytest.raises(OSError):
        mf.commit_reference(d, staged, "k", entry)
    assert journal_seen == [True]
    assert (d / "k.exr").read_bytes() == b"old reference" and _consistent(mf, d) == 1
    # a process killed outright leaves its journal: it is ignored while the old file is in place
    (d / mf.PENDING_NAME).write_text(json.dumps({"schema": mf.SCHEMA, "references": {"k": entry},
                                                 "pending": {"key": "k", "file": "k.exr", "sha256": entry["sha256"]}}))
    assert _consistent(mf, d) == 1
    monkeypatch.undo()
    mf.commit_reference(d, staged, "k", entry)  # the next commit drops the stale journal, then commits
    assert _consistent(mf, d) == 2 and not (d / mf.PENDING_NAME).exists() and not staged.exists()


def test_build_killed_between_exr_and_manifest(tmp_path, monkeypatch):
    """The whole build: the committed pair loads after a crash between the two writes."""
    import mcrt.groundtruth as ref
    from mcrt.groundtruth import manifest as mf

    scene = load_scene()
    b = ref.build_reference(scene, "near", 8, 2, 8, chunk_spp=4, directory=tmp_path, workers=1, progress=False)
    monkeypatch.setattr(mf, "write_manifest", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        ref.build_reference(scene, "near", 8, 2, 16, chunk_spp=4, directory=tmp_path, workers=1, progress=False)
    monkeypatch.undo()
    r = ref.load_reference(scene, "near", 8, 2, directory=tmp_path)  # checksum and contents agree
    assert r.spp == 16 and b.result.spp == 8
    assert not list(tmp_path.glob(".*.tmp"))
