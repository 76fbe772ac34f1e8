"""``mcrt gradescope-zip``: the autograder zip for Gradescope, from a checkout or a normal install.

    mcrt gradescope-zip [ASSIGNMENT [FILE...]] [--mode image|code] [--out ZIP]
    mcrt gradescope-zip --write-lock FILE

The zip holds, at its root:

    setup.sh, run_autograder   Gradescope's two scripts (the package's assignments/gradescope/)
    requirements.lock          the exact versions setup.sh installs (pip --no-deps -r), nothing else
    assignment.toml            the assignment, as given (FILE...: files shipped beside it, a scene say)
    mode                       "image" or "code": what run_autograder grades
    mcrt-<version>-*.whl       this mcrt as a wheel

The wheel is built from the source checkout this mcrt is imported from (``pip wheel`` of its working tree) or,
for a normal install, packed from the installed distribution's own files, each checked against the hash its
RECORD holds (a changed installation is refused). No copy of a repository goes in: nothing named mcrt/ can shadow
the installed package.

The lock pins mcrt's dependencies and theirs, as installed in the environment that runs this command, except those
grading never imports (:data:`LEFT_OUT`). The zip ships the package's own copy, beside setup.sh in the package
data's assignments/gradescope/ folder; ``--write-lock`` regenerates it from a working environment:

    mcrt gradescope-zip --write-lock requirements.lock

Exit codes: 0 written, 2 unusable input (no such assignment, a FILE missing, an assignment that does not load
from the zip's folder, an installation that cannot be packed).
"""

from __future__ import annotations

import argparse
import base64
import csv
import hashlib
import io
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from importlib import metadata
from pathlib import Path

from mcrt.exitcodes import EXIT_OK, EXIT_UNUSABLE
from mcrt.grade.assignment import ASSIGNMENT_DIR, AssignmentError, load_assignment

#: Gradescope's scripts and the lock, as package data.
GRADESCOPE_DIR = ASSIGNMENT_DIR / "gradescope"
LOCK = GRADESCOPE_DIR / "requirements.lock"
#: mcrt's dependencies that grading never imports (reports' plots, reference builds on a Dask cluster): not in the
#: image; and pip, which every virtual environment has of its own.
LEFT_OUT = frozenset({"matplotlib", "dask", "pip"})
DEFAULT_OUT = "autograder.zip"
DEFAULT_ASSIGNMENT = {"image": "course2023", "code": "course2023_code"}


class ZipError(RuntimeError):
    """The zip cannot be built; the message says why."""


def grading_requirements() -> dict[str, str]:
    """{distribution name: installed version} of mcrt's dependencies and theirs (with the extras asked for), less
    :data:`LEFT_OUT`; markers are evaluated for this interpreter and platform."""
    from packaging.requirements import Requirement  # a dependency of scikit-image, so in every mcrt environment
    from packaging.utils import canonicalize_name

    found: dict[str, str] = {}
    seen: set[tuple[str, str]] = set()
    todo = [(r, "") for r in metadata.requires("mcrt") or []]  # (Requires-Dist line, extra of the distribution naming it)
    while todo:
        line, extra = todo.pop()
        req = Requirement(line)
        name = canonicalize_name(req.name)
        if name in LEFT_OUT or (req.marker is not None and not req.marker.evaluate({"extra": extra})):
            continue
        try:
            dist = metadata.distribution(name)
        except metadata.PackageNotFoundError:
            raise ZipError(f"{name}, a dependency of mcrt, is not installed here, so it cannot be pinned") from None
        found[name] = dist.version
        for e in {"", *req.extras} - {x for n, x in seen if n == name}:
            seen.add((name, e))
            todo += [(r, e) for r in dist.requires or []]
    return {dist_name(n): v for n, v in sorted(found.items())}


def dist_name(canonical: str) -> str:
    """The distribution's own spelling of its name (as pip freeze writes it)."""
    return metadata.distribution(canonical).metadata["Name"]


def write_lock(path: Path) -> str:
    """Write :func:`grading_requirements` as ``name==version`` lines to ``path``; returns the text."""
    pins = grading_requirements()
    text = ("# What setup.sh installs into the Gradescope image (pip install --no-deps -r): mcrt's dependencies and\n"
            f"# theirs, less those grading never imports or the venv has ({', '.join(sorted(LEFT_OUT))}), at tested versions.\n"
            "# Regenerate from a working environment: mcrt gradescope-zip --write-lock FILE\n"
            + "".join(f"{n}=={v}\n" for n, v in pins.items()))
    Path(path).write_text(text, encoding="utf-8")
    return text


# --------------------------------------------------------------------------
# The wheel: from the checkout, or packed from the installed files
# --------------------------------------------------------------------------


def source_checkout() -> Path | None:
    """The source checkout this mcrt is imported from (its pyproject.toml names the project mcrt), else None."""
    root = Path(__file__).resolve().parents[2]
    pyproject = root / "pyproject.toml"
    if pyproject.is_file() and re.search(r'(?m)^name\s*=\s*"mcrt"', pyproject.read_text(encoding="utf-8")):
        return root
    return None


def build_wheel(out_dir: Path) -> Path:
    """mcrt as a wheel in ``out_dir``: ``pip wheel`` of the checkout, else the installed distribution repacked."""
    root = source_checkout()
    if root is not None:
        r = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out_dir), str(root)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise ZipError(f"pip wheel {root} failed: {(r.stderr or r.stdout).strip().splitlines()[-1:]}")
        return next(out_dir.glob("mcrt-*.whl"))
    return repack_installed(out_dir)


#: Files of an installed distribution that the installer made, not the wheel: they are not packed.
_INSTALLER_FILES = {"INSTALLER", "RECORD", "REQUESTED", "direct_url.json"}


def repack_installed(out_dir: Path) -> Path:
    """The installed mcrt packed back into a wheel (pure Python: ``py3-none-any``), from its RECORD.

    Written here rather than with the ``wheel`` package's ``pack`` (not a dependency, and it wants an unpacked
    wheel's layout): a wheel is a zip of the installed files with a RECORD of their hashes. Every file is checked
    against the hash the installation recorded, so what is shipped is what was installed.
    """
    dist = metadata.distribution("mcrt")
    files = dist.files or []
    info = next((f for f in files if f.parts[0].endswith(".dist-info")), None)
    if info is None or not any(f.parts[0] == "mcrt" for f in files):
        raise ZipError("this mcrt is neither a source checkout nor a normal install with its files listed "
                       "(an editable install without its checkout?): run the command from a checkout or after pip install")
    info_dir = info.parts[0]
    name = f"mcrt-{dist.version}-py3-none-any.whl"
    record = io.StringIO()
    rec = csv.writer(record, lineterminator="\n")
    out = out_dir / name
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for f in files:
            if f.parts[0] not in ("mcrt", info_dir) or "__pycache__" in f.parts or f.name in _INSTALLER_FILES:
                continue  # the console script, .pyc files and the installer's records are the installer's, not the wheel's
            data = f.locate().read_bytes()
            if f.hash is not None:
                got = hashlib.new(f.hash.mode, data).digest()
                if base64.urlsafe_b64encode(got).rstrip(b"=").decode() != f.hash.value:
                    raise ZipError(f"{f.locate()}: changed since mcrt was installed; reinstall mcrt, or build from a checkout")
            z.writestr(str(f), data)
            digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            rec.writerow([str(f), f"sha256={digest}", len(data)])
        rec.writerow([f"{info_dir}/RECORD", "", ""])
        z.writestr(f"{info_dir}/RECORD", record.getvalue())
    return out


# --------------------------------------------------------------------------
# The zip
# --------------------------------------------------------------------------


def build_zip(assignment: str | Path, out: str | Path, *, mode: str = "image", extra: tuple[str | Path, ...] = (),
              log=lambda s: None) -> Path:
    """Write Gradescope's autograder.zip to ``out`` (see the module docstring); returns its path."""
    if mode not in DEFAULT_ASSIGNMENT:
        raise ZipError(f"--mode must be image or code, got {mode}")
    try:
        a = load_assignment(assignment)
    except AssignmentError as e:
        raise ZipError(str(e)) from None
    out = Path(out).resolve()
    with tempfile.TemporaryDirectory(prefix="mcrt-zip-") as tmp:
        stage = Path(tmp)
        for f in extra:
            if not Path(f).is_file():
                raise ZipError(f"{f}: no such file")
            shutil.copy(f, stage / Path(f).name)
        shutil.copy(a.path, stage / "assignment.toml")
        # The assignment must load where Gradescope will read it (its scene found, its [code] table there for code mode).
        try:
            staged = load_assignment(stage / "assignment.toml")
            staged.load_scene()
        except AssignmentError as e:
            raise ZipError(f"the assignment does not load from the zip: {e} (a scene of the package is named without "
                           ".toml; another scene file must be shipped: mcrt gradescope-zip A.toml SCENE.toml)") from None
        if mode == "code" and staged.code is None:
            raise ZipError(f"--mode code, but {a.path} has no [code] table")
        (stage / "mode").write_text(mode + "\n")
        for script in ("setup.sh", "run_autograder", "requirements.lock"):
            shutil.copy(GRADESCOPE_DIR / script, stage / script)
        log("building the mcrt wheel" + (f" from {source_checkout()}" if source_checkout() else " from the installed files"))
        wheel = build_wheel(stage)
        out.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
            for p in sorted(stage.iterdir()):
                info = zipfile.ZipInfo(p.name, date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = (0o100755 if p.name in ("setup.sh", "run_autograder") else 0o100644) << 16
                z.writestr(info, p.read_bytes())
        log(f"wheel {wheel.name}")
    return out


def register(sub) -> None:
    p = sub.add_parser("gradescope-zip", help="build Gradescope's autograder.zip (setup.sh, run_autograder, the assignment, "
                       "mcrt as a wheel, the pinned versions) from this checkout or installation",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("assignment", nargs="?", default=None,
                   help="assignment: a name of the package's assignments or a file (default: course2023, "
                   "course2023_code with --mode code)")
    p.add_argument("files", nargs="*", metavar="FILE", help="files shipped beside assignment.toml, e.g. the scene file "
                   "its [scene] file names by a relative path (default: none)")
    p.add_argument("--mode", choices=tuple(DEFAULT_ASSIGNMENT), default="image",
                   help="what run_autograder grades: image renders or Python modules (default: image)")
    p.add_argument("--out", "-o", default=DEFAULT_OUT, help=f"the zip to write (default: ./{DEFAULT_OUT})")
    p.add_argument("--write-lock", metavar="FILE", default=None,
                   help="only write the pins of this environment's grading dependencies to FILE, the zip's "
                   "requirements.lock, and exit (default: off)")
    p.set_defaults(func=run)


def run(args) -> int:
    try:
        if args.write_lock:
            text = write_lock(Path(args.write_lock))
            print(f"wrote {args.write_lock} ({sum(1 for ln in text.splitlines() if '==' in ln)} pins)")
            return EXIT_OK
        out = build_zip(args.assignment or DEFAULT_ASSIGNMENT[args.mode], args.out, mode=args.mode,
                        extra=tuple(args.files), log=lambda s: print(f"mcrt gradescope-zip: {s}", file=sys.stderr))
    except (ZipError, OSError) as e:
        print(f"mcrt gradescope-zip: {e}", file=sys.stderr)
        return EXIT_UNUSABLE
    print(f"wrote {out} ({args.mode} mode, {Path(args.assignment or DEFAULT_ASSIGNMENT[args.mode]).name})")
    return EXIT_OK
