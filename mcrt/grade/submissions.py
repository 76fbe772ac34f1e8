"""Finding students' submissions and reading their manifests.

Layouts of ``SUBMISSIONS`` (see :func:`discover`):

* one file: one student, whose id is the file's stem;
* a folder: every image file in it is one student (id: the stem), every
  sub-folder is one student (id: the folder's name); a ``<stem>.toml`` or
  ``<stem>.json`` beside ``<stem>.exr`` is that student's manifest;
  symbolic links, FIFOs, sockets and devices are never followed or opened:
  each becomes a student graded 0 with a message saying what it is (inside
  a student's folder they are left out, with a note);
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
:class:`Submission` and are graded. File names that are not valid UTF-8
appear in messages with U+FFFD in place of the bad bytes (:func:`shown`).
"""

from __future__ import annotations

import json
import os
import re
import stat
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

HDR_EXTS = (".exr", ".pfm", ".hdr", ".pic", ".rgbe")
LDR_EXTS = (".png", ".ppm", ".pnm", ".pgm", ".bmp", ".tga")  # 8 or 16 bit, sRGB unless declared linear
JPEG_EXTS = (".jpg", ".jpeg", ".jpe", ".jfif")  # refused, with the reason (mcrt.image_files.JPEG_REASON)
IMAGE_EXTS = HDR_EXTS + LDR_EXTS
SUPPORTED = ("OpenEXR (.exr), PFM (.pfm), Radiance HDR (.hdr), PNG (.png, 8 or 16 bit), PPM (.ppm, P3 or P6), "
             "BMP (.bmp) or TGA (.tga)")
MANIFEST_EXTS = (".toml", ".json")
MANIFEST_KEYS = {"spp", "seed", "seeds", "camera", "linear", "images", "notes", "renderer", "name"}
MAX_MANIFEST_BYTES = 64 * 1024
MAX_MANIFEST_DEPTH = 8  # no field needs more than a list; deeper data is refused before anything walks it


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
    special: str | None = None  # a link or special file where the hand-in should be: what it is (for the summary)


#: Names the class-level outputs use in DIR; a student id never takes one.
RESERVED = {"grades.csv", "summary.md", "summary.json", "grading.log", "run.json"}


def shown(name: str) -> str:
    """``name`` as valid UTF-8 text: bytes that are not UTF-8 (surrogate-escaped by the OS layer) become U+FFFD."""
    return str(name).encode("utf-8", "surrogateescape").decode("utf-8", "replace")


def file_kind(p: str | os.PathLike) -> str | None:
    """None for a regular file or a folder (not a link); otherwise what it is, in words, for a student.

    Only ``lstat`` is used (and ``stat`` of a link's target, which opens
    nothing), so a FIFO cannot block and a link is never followed.
    """
    try:
        st = os.lstat(p)
    except OSError as e:
        return f"cannot be examined ({e.strerror or e})"
    if stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode):
        return None
    if stat.S_ISLNK(st.st_mode):
        try:
            target = os.stat(p)
        except OSError:
            return "a broken symbolic link (its target does not exist)"
        return f"a symbolic link (to {_kind_words(target.st_mode)})"
    return _kind_words(st.st_mode)


def _kind_words(mode: int) -> str:
    if stat.S_ISREG(mode):
        return "a regular file"
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a special file"


def _special_problem(name: str, kind: str) -> str:
    return (f"{shown(name)} is {kind}, not a regular file; links and special files are not followed or opened: "
            "hand in the image file itself")


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
    if not root.is_dir():  # SUBMISSIONS itself is the instructor's choice: a link to it is followed
        if not root.is_file():
            kind = _kind_words(os.stat(root).st_mode)
            return [Submission(safe_id(student or root.stem), str(root), problem=_special_problem(root.name, kind), special=kind)]
        real = root.resolve()  # never a link: the grader opens regular files only
        return [_from_files(student or root.stem, str(root), [real], manifest=_sibling_manifest(root))]
    if single:
        return [_from_folder(student or root.name, root)]
    entries = sorted((p for p in root.iterdir() if _visible(p)), key=lambda p: p.name)
    kinds = {p: file_kind(p) for p in entries}
    stems_with_images = {p.stem for p in entries if kinds[p] is None and p.is_file() and p.suffix.lower() in IMAGE_EXTS}
    subs: list[Submission] = []
    for p in entries:
        if kinds[p] is not None:  # a link, FIFO, socket or device: reported, never followed or opened
            if p.suffix.lower() in MANIFEST_EXTS and p.stem in stems_with_images:
                continue  # reported in that student's notes instead
            subs.append(Submission(safe_id(p.stem if p.suffix else p.name), str(p), problem=_special_problem(p.name, kinds[p]),
                                   special=kinds[p]))
        elif p.is_dir():
            subs.append(_from_folder(p.name, p))
        else:
            if p.suffix.lower() in MANIFEST_EXTS and p.stem in stems_with_images:
                continue  # a manifest beside its image
            subs.append(_from_files(p.stem, str(p), [p], manifest=_sibling_manifest(p)))
    ids = _unique([safe_id(s.student) for s in subs])
    for s, i in zip(subs, ids):
        if i != s.student:
            s.notes.append(f"student id {shown(s.student)!r} is stored as {i!r}")
        s.student = i
    return sorted(subs, key=lambda s: s.student)


def _sibling_manifest(p: Path) -> Path | None:
    for ext in MANIFEST_EXTS:
        m = p.with_suffix(ext)
        if m != p and file_kind(m) is None and m.is_file():
            return m
    return None


def _no_image_problem(files: list[Path], found: str = "") -> str:
    jpegs = [f for f in files if f.suffix.lower() in JPEG_EXTS]
    if jpegs:
        from mcrt.image_files import JPEG_REASON

        return f"no image in a supported format: {shown(jpegs[0].name)}: {JPEG_REASON}"
    kinds = ", ".join(sorted({shown(f.suffix.lower()) or "(no extension)" for f in files}))
    return f"no image in a supported format ({found}{kinds}); hand in {SUPPORTED}"


def _from_files(student: str, source: str, files: list[Path], manifest: Path | None) -> Submission:
    sub = Submission(safe_id(student), source, manifest_path=str(manifest) if manifest else None)
    images = [f for f in files if f.suffix.lower() in IMAGE_EXTS]
    if not images:
        sub.problem = _no_image_problem(files)
        # Still try to read it: a mislabelled EXR deserves a precise message (a JPEG's reason is the message).
        sub.images = [str(files[0])] if files and files[0].suffix.lower() not in JPEG_EXTS else []
        return sub
    sub.images = [str(f) for f in images]
    return sub


def _from_folder(student: str, folder: Path) -> Submission:
    files, special, err = _walk(folder)
    if err is not None:
        return Submission(safe_id(student), str(folder), problem=f"cannot list the folder ({err})")
    manifests = [f for f in files if f.suffix.lower() in MANIFEST_EXTS]
    named = [f for f in manifests if f.stem.lower() == "manifest"]
    manifest = (named or manifests or [None])[0]
    sub = Submission(safe_id(student), str(folder), manifest_path=str(manifest) if manifest else None)
    for p, kind in special:
        sub.notes.append(f"{shown(str(p.relative_to(folder)))} is {kind}, not a regular file: left out "
                         "(links and special files are not followed or opened)")
    if len(manifests) > 1:
        sub.notes.append(f"several manifests found; used {shown(manifest.name)}")
    images = [f for f in files if f.suffix.lower() in IMAGE_EXTS]
    if not images:
        others = [f for f in files if f not in manifests]
        special_images = [p for p, _ in special if p.suffix.lower() in IMAGE_EXTS + JPEG_EXTS]
        if special_images:
            p = special_images[0]
            sub.special = dict(special)[p]
            sub.problem = _special_problem(str(p.relative_to(folder)), sub.special)
        elif not others:
            sub.problem = "the folder holds no image"
        else:
            sub.problem = _no_image_problem(others, "found ")
            sub.images = [str(others[0])] if others[0].suffix.lower() not in JPEG_EXTS else []
        return sub
    jpegs = [f for f in files if f.suffix.lower() in JPEG_EXTS]
    if jpegs:
        sub.notes.append(f"{', '.join(shown(f.name) for f in jpegs)}: JPEG files are not graded (lossy); graded "
                         + ", ".join(shown(f.name) for f in images[:2]))
    sub.images = [str(f) for f in images]
    return sub


def _walk(folder: Path) -> tuple[list[Path], list[tuple[Path, str]], str | None]:
    """Regular files under ``folder`` (hidden names left out), the links and special files met, or an error.

    Symbolic links, to files or to folders, are never followed (``os.walk``
    with ``followlinks=False``, every entry classified by ``lstat``).
    """
    files: list[Path] = []
    special: list[tuple[Path, str]] = []
    errors: list[OSError] = []
    for dirpath, dirnames, filenames in os.walk(folder, onerror=errors.append, followlinks=False):
        base = Path(dirpath)
        keep = []
        for d in sorted(dirnames):
            if not _visible(d):
                continue
            kind = file_kind(base / d)
            if kind is None:
                keep.append(d)
            else:  # a link to a folder: os.walk lists it here and would not descend, but say so
                special.append((base / d, kind))
        dirnames[:] = keep
        for f in sorted(filenames):
            if not _visible(f):
                continue
            kind = file_kind(base / f)
            (files.append(base / f) if kind is None else special.append((base / f, kind)))
    if errors and not files:
        e = errors[0]
        return [], [], str(e.strerror or e)
    files.sort(key=lambda p: str(p.relative_to(folder)))
    return files, special, None


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
                inside = p.resolve().is_relative_to(base.resolve()) and not any(
                    file_kind(q) for q in [p, *p.parents] if q.is_relative_to(base) and q != base)
            except (OSError, ValueError):
                inside = False
            if not inside:
                notes.append(f"manifest names {name!r}, which is outside the submission (or a link); ignored")
            elif not p.is_file():
                notes.append(f"manifest names {name!r}, which is not in the submission; ignored")
            else:
                chosen.append(str(p))
        if chosen:
            return chosen, notes
    if len(images) > 2 or (len(images) == 2 and _mixed(images)):
        hdr = [i for i in images if Path(i).suffix.lower() in HDR_EXTS]
        if hdr and len(hdr) < len(images):
            notes.append("8/16-bit images (PNG, PPM, BMP, TGA) next to HDR renders were taken as previews and not graded: "
                         + ", ".join(shown(Path(i).name) for i in images if i not in hdr))
            images = hdr
    if len(images) > 2:
        notes.append(f"{len(images)} images found; graded the first two ({', '.join(shown(Path(i).name) for i in images[:2])}); "
                     "list the renders in the manifest's 'images' to choose")
        images = images[:2]
    return images, notes


def _mixed(images: list[str]) -> bool:
    return len({Path(i).suffix.lower() in HDR_EXTS for i in images}) > 1


def _check_depth(data, limit: int) -> None:
    """Raise ValueError when lists or tables nest more than ``limit`` levels (iteratively: no recursion)."""
    stack = [(data, 0)]
    while stack:
        x, d = stack.pop()
        if isinstance(x, (list, dict)):
            if d >= limit:
                raise ValueError("too deep")
            stack.extend((v, d + 1) for v in (x.values() if isinstance(x, dict) else x))


def read_manifest(path: str | None) -> Manifest:
    """Parse a manifest leniently: problems become warnings, never exceptions."""
    m = Manifest()
    if path is None:
        return m
    name = shown(Path(path).name)
    kind = file_kind(path)
    if kind is not None:
        m.warnings.append(f"manifest {name}: is {kind}, not a regular file; ignored")
        return m
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise OSError("not a regular file")
            raw = f.read(MAX_MANIFEST_BYTES + 1)
    except OSError as e:
        m.warnings.append(f"manifest {name}: cannot read ({shown(e.strerror or e)}); ignored")
        return m
    if len(raw) > MAX_MANIFEST_BYTES:
        m.warnings.append(f"manifest {name}: larger than {MAX_MANIFEST_BYTES // 1024} KiB; ignored")
        return m
    lang = "JSON" if name.lower().endswith(".json") else "TOML"
    try:
        text = raw.decode("utf-8")
        data = json.loads(text) if lang == "JSON" else tomllib.loads(text)
    except (UnicodeDecodeError, json.JSONDecodeError, tomllib.TOMLDecodeError) as e:
        m.warnings.append(f"manifest {name}: not valid {lang} ({shown(' '.join(str(e).split())[:120])}); ignored")
        return m
    except (RecursionError, MemoryError):
        m.warnings.append(f"manifest {name}: nested too deeply to read (arrays or tables inside one another "
                          f"hundreds of levels deep); ignored")
        return m
    try:
        _check_depth(data, MAX_MANIFEST_DEPTH)
    except ValueError:
        m.warnings.append(f"manifest {name}: nested more than {MAX_MANIFEST_DEPTH} levels deep; ignored")
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
