"""Finding students' submissions and reading their manifests.

Layouts of ``SUBMISSIONS`` (see :func:`discover`):

* one file: one student, whose id is the file's stem;
* a folder: every image file in it is one student (id: the stem), every
  sub-folder is one student (id: the folder's name); a ``<stem>.toml`` or
  ``<stem>.json`` beside ``<stem>.exr`` is that student's manifest;
* with ``single=True``: the folder is one student's hand-in (Gradescope's
  ``/autograder/submission``).

A student's folder holds one render, or two independent renders of the same
image (their difference measures the noise), and optionally a manifest
(``manifest.toml`` or ``manifest.json``, or the only ``.toml``/``.json``
file) with these fields, all optional::

    spp = 100                 # samples per pixel of each render
    seed = 1                  # seeds, for the record ("seeds = [1, 2]" for two renders)
    camera = "near"           # the camera rendered
    linear = false            # PNG only: the PNG holds linear values, not sRGB
    images = ["a.exr", "b.exr"]  # which files are the renders (else: found by extension)
    notes = "30 shadow rays per vertex"

Nothing here raises on bad student input: problems become notes on the
:class:`Submission` and are graded.
"""

from __future__ import annotations

import json
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

IMAGE_EXTS = (".exr", ".pfm", ".hdr", ".pic", ".rgbe", ".png")
HDR_EXTS = (".exr", ".pfm", ".hdr", ".pic", ".rgbe")
MANIFEST_EXTS = (".toml", ".json")
MANIFEST_KEYS = {"spp", "seed", "seeds", "camera", "linear", "images", "notes", "renderer", "name"}
MAX_MANIFEST_BYTES = 64 * 1024


@dataclass
class Manifest:
    spp: int | None = None
    seeds: tuple[int, ...] = ()
    camera: str | None = None
    linear: bool | None = None
    images: tuple[str, ...] = ()
    notes: str = ""
    warnings: list[str] = field(default_factory=list)


@dataclass
class Submission:
    """One student's hand-in: chosen image files, manifest, discovery notes."""

    student: str  # safe id: used as a folder name under --out
    source: str  # what was found in SUBMISSIONS (file or folder)
    images: list[str] = field(default_factory=list)
    manifest_path: str | None = None
    notes: list[str] = field(default_factory=list)
    problem: str | None = None  # no usable image: graded zero with this message


#: Names the class-level outputs use in DIR; a student id never takes one.
RESERVED = {"grades.csv", "summary.md", "summary.json", "grading.log"}


def safe_id(name: str) -> str:
    """A student id usable as a folder name: letters, digits and ``._@-`` only, never an output's name."""
    s = re.sub(r"[^A-Za-z0-9._@-]", "_", name).lstrip(".")
    s = s[:100] or "student"
    return f"{s}-student" if s.lower() in RESERVED else s


def _unique(ids: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for i in ids:
        n = seen.get(i, 0)
        seen[i] = n + 1
        out.append(i if n == 0 else f"{i}-{n + 1}")
    return out


def _visible(p: Path | str) -> bool:
    name = p if isinstance(p, str) else p.name
    return not name.startswith(".") and not name.startswith("__")


def discover(path: str | os.PathLike, *, single: bool = False, student: str | None = None) -> list[Submission]:
    """The submissions under ``path`` (see the module docstring), sorted by student id.

    Raises FileNotFoundError when ``path`` does not exist; everything else
    about a student's files is recorded on their :class:`Submission`.
    """
    root = Path(path)
    if not root.exists():
        raise FileNotFoundError(f"{root}: no such file or folder")
    if root.is_file():
        return [_from_files(student or root.stem, str(root), [root], manifest=_sibling_manifest(root))]
    if single:
        return [_from_folder(student or root.name, root)]
    entries = sorted((p for p in root.iterdir() if _visible(p)), key=lambda p: p.name)
    stems_with_images = {p.stem for p in entries if p.is_file() and p.suffix.lower() in IMAGE_EXTS}
    subs: list[Submission] = []
    for p in entries:
        if p.is_dir():
            subs.append(_from_folder(p.name, p))
        elif p.is_file():
            if p.suffix.lower() in MANIFEST_EXTS and p.stem in stems_with_images:
                continue  # a manifest beside its image
            subs.append(_from_files(p.stem, str(p), [p], manifest=_sibling_manifest(p)))
    ids = _unique([safe_id(s.student) for s in subs])
    for s, i in zip(subs, ids):
        if i != s.student:
            s.notes.append(f"student id {s.student!r} is stored as {i!r}")
        s.student = i
    return sorted(subs, key=lambda s: s.student)


def _sibling_manifest(p: Path) -> Path | None:
    for ext in MANIFEST_EXTS:
        m = p.with_suffix(ext)
        if m != p and m.is_file():
            return m
    return None


def _from_files(student: str, source: str, files: list[Path], manifest: Path | None) -> Submission:
    sub = Submission(safe_id(student), source, manifest_path=str(manifest) if manifest else None)
    images = [f for f in files if f.suffix.lower() in IMAGE_EXTS]
    if not images:
        kinds = ", ".join(sorted({f.suffix.lower() or "(no extension)" for f in files}))
        sub.problem = (f"no image in a supported format ({kinds}); hand in OpenEXR (.exr), PFM (.pfm), "
                       f"Radiance HDR (.hdr) or PNG (.png)")
        # Still try to read it: a mislabelled EXR deserves a precise message.
        sub.images = [str(files[0])] if files else []
        return sub
    sub.images = [str(f) for f in images]
    return sub


def _from_folder(student: str, folder: Path) -> Submission:
    try:
        files = sorted((p for p in folder.rglob("*") if p.is_file() and all(_visible(q) for q in p.relative_to(folder).parts)),
                       key=lambda p: str(p.relative_to(folder)))
    except OSError as e:
        return Submission(safe_id(student), str(folder), problem=f"cannot list the folder ({e.strerror or e})")
    manifests = [f for f in files if f.suffix.lower() in MANIFEST_EXTS]
    named = [f for f in manifests if f.stem.lower() == "manifest"]
    manifest = (named or manifests or [None])[0]
    sub = Submission(safe_id(student), str(folder), manifest_path=str(manifest) if manifest else None)
    if len(manifests) > 1:
        sub.notes.append(f"several manifests found; used {manifest.name}")
    images = [f for f in files if f.suffix.lower() in IMAGE_EXTS]
    if not images:
        others = [f for f in files if f not in manifests]
        if not others:
            sub.problem = "the folder holds no image"
        else:
            kinds = ", ".join(sorted({f.suffix.lower() or "(no extension)" for f in others}))
            sub.problem = (f"no image in a supported format (found {kinds}); hand in OpenEXR (.exr), PFM (.pfm), "
                           f"Radiance HDR (.hdr) or PNG (.png)")
            sub.images = [str(others[0])]
        return sub
    sub.images = [str(f) for f in images]
    return sub


def choose_images(sub: Submission, manifest: Manifest) -> tuple[list[str], list[str]]:
    """The (at most two) render files to grade, and notes on the choice."""
    notes: list[str] = []
    images = list(sub.images)
    if manifest.images:
        base = Path(sub.source) if Path(sub.source).is_dir() else Path(sub.source).parent
        chosen = []
        for name in manifest.images[:2]:
            p = (base / name)
            try:
                inside = p.resolve().is_relative_to(base.resolve())
            except OSError:
                inside = False
            if not inside:
                notes.append(f"manifest names {name!r}, which is outside the submission; ignored")
            elif not p.is_file():
                notes.append(f"manifest names {name!r}, which is not in the submission; ignored")
            else:
                chosen.append(str(p))
        if chosen:
            return chosen, notes
    if len(images) > 2 or (len(images) == 2 and _mixed(images)):
        hdr = [i for i in images if Path(i).suffix.lower() in HDR_EXTS]
        if hdr and len(hdr) < len(images):
            notes.append("PNG files next to HDR renders were taken as previews and not graded: "
                         + ", ".join(Path(i).name for i in images if i not in hdr))
            images = hdr
    if len(images) > 2:
        notes.append(f"{len(images)} images found; graded the first two ({', '.join(Path(i).name for i in images[:2])}); "
                     "list the renders in the manifest's 'images' to choose")
        images = images[:2]
    return images, notes


def _mixed(images: list[str]) -> bool:
    return len({Path(i).suffix.lower() in HDR_EXTS for i in images}) > 1


def read_manifest(path: str | None) -> Manifest:
    """Parse a manifest leniently: problems become warnings, never exceptions."""
    m = Manifest()
    if path is None:
        return m
    name = Path(path).name
    try:
        raw = Path(path).read_bytes()[: MAX_MANIFEST_BYTES + 1]
    except OSError as e:
        m.warnings.append(f"manifest {name}: cannot read ({e.strerror or e}); ignored")
        return m
    if len(raw) > MAX_MANIFEST_BYTES:
        m.warnings.append(f"manifest {name}: larger than {MAX_MANIFEST_BYTES // 1024} KiB; ignored")
        return m
    try:
        text = raw.decode("utf-8")
        data = json.loads(text) if name.lower().endswith(".json") else tomllib.loads(text)
    except (UnicodeDecodeError, json.JSONDecodeError, tomllib.TOMLDecodeError) as e:
        m.warnings.append(f"manifest {name}: not valid {'JSON' if name.lower().endswith('.json') else 'TOML'} "
                          f"({' '.join(str(e).split())[:120]}); ignored")
        return m
    if not isinstance(data, dict):
        m.warnings.append(f"manifest {name}: expected a table of fields; ignored")
        return m
    for k in data:
        if k not in MANIFEST_KEYS:
            m.warnings.append(f"manifest {name}: unknown field {k!r} ignored (known: {', '.join(sorted(MANIFEST_KEYS))})")
    spp = data.get("spp")
    if spp is not None:
        if isinstance(spp, bool) or not isinstance(spp, int) or spp < 1:
            m.warnings.append(f"manifest {name}: spp must be a positive integer, got {spp!r}; ignored")
        else:
            m.spp = spp
    seeds = data.get("seeds", [data["seed"]] if "seed" in data else [])
    if isinstance(seeds, list) and all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
        m.seeds = tuple(seeds)
    else:
        m.warnings.append(f"manifest {name}: seed(s) must be integers, got {seeds!r}; ignored")
    cam = data.get("camera")
    if cam is not None:
        if isinstance(cam, str) and cam:
            m.camera = cam
        else:
            m.warnings.append(f"manifest {name}: camera must be a name, got {cam!r}; ignored")
    lin = data.get("linear")
    if lin is not None:
        if isinstance(lin, bool):
            m.linear = lin
        else:
            m.warnings.append(f"manifest {name}: linear must be true or false, got {lin!r}; ignored")
    imgs = data.get("images")
    if imgs is not None:
        if isinstance(imgs, list) and all(isinstance(i, str) for i in imgs) and imgs:
            m.images = tuple(imgs)
        else:
            m.warnings.append(f"manifest {name}: images must be a list of file names, got {imgs!r}; ignored")
    notes = data.get("notes", "")
    m.notes = " ".join(str(notes).split())[:2000]
    return m
