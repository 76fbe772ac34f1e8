"""Gradescope end to end, and a normal install grading from a folder outside the checkout.

``mcrt gradescope-zip`` builds autograder.zip from this checkout (a wheel,
the two scripts, the lock, a small 16x16 assignment); the zip
is unpacked into a simulated ``/autograder`` in a temporary folder
(``AUTOGRADER_ROOT``), ``setup.sh`` runs there in its explicit test mode
(``MCRT_SETUP_DEPS``: the dependencies come from this environment's
site-packages, nothing is downloaded and apt-get is not run; the interpreter
is this one, ``MCRT_SETUP_PYTHON``) and ``run_autograder`` grades a correct
render, a biased one, an unreadable file and, from a second zip built with
``--mode code``, a Python module. Every results.json is checked against
Gradescope's specification of the format (keys, types, formats,
visibilities, the score the sum of the tests') and for the feedback that
matters in it: the diagnosis, the map of where the image differs, what to do.
A folder named ``mcrt`` whose import fails sits in Gradescope's working
folder (/autograder) and in the class's folder: it must never shadow the
installed package.

The same wheel, unpacked and imported with ``python -S`` (so the editable
install of the checkout is not on the path), grades a small class with two
worker processes from a folder outside the checkout.

The tests that build a zip or a wheel are ``long`` (minutes together: each
builds a wheel and a venv): they run with ``MCRT_SLOW=1``, as in CI.
"""

from __future__ import annotations

import json
import os
import shutil
import site
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from mcrt.image_files import write_exr
from mcrt.llvm import find_llvm
from mcrt.render import render
from mcrt.scene import load_scene
from test_grade import ASSIGNMENT as TEST_GRADE_ASSIGNMENT
from test_grade import GOOD

ROOT = Path(__file__).resolve().parent.parent
GRADESCOPE = ROOT / "reference" / "assignments" / "gradescope"
RES = 16
# test_grade's class assignment, at 16x16 and with a smaller catalogue render (setup.sh prepares it in seconds).
_SMALLER = {'name = "test32"': 'name = "gs16"', "width = 32": f"width = {RES}", "height = 32": f"height = {RES}",
            "tiles = [8, 16, 0]": "tiles = [8, 0]", "diagnosis_spp = 4096": "diagnosis_spp = 256",
            "reference_spp = 4096": "reference_spp = 1024"}
ASSIGNMENT = TEST_GRADE_ASSIGNMENT
for _old, _new in _SMALLER.items():
    assert _old in ASSIGNMENT, _old
    ASSIGNMENT = ASSIGNMENT.replace(_old, _new)

# Gradescope's results.json (https://gradescope-autograders.readthedocs.io/en/latest/specs/).
FORMATS = {"text", "html", "simple_format", "md", "ansi"}
VISIBILITIES = {"hidden", "after_due_date", "after_published", "visible"}
TOP_KEYS = {"score", "execution_time", "output", "output_format", "test_output_format", "test_name_format", "visibility",
            "stdout_visibility", "extra_data", "tests", "leaderboard"} | {"max_score"}  # max_score: ours, kept for grades
TEST_KEYS = {"score", "max_score", "status", "name", "name_format", "number", "output", "output_format", "tags",
             "visibility", "extra_data"}
# Where this environment's packages are: its site-packages and those its .pth files add (a worktree's venv takes
# its dependencies from another venv's), for venvs that borrow them.
DEPS = [p for p in sys.path if p.endswith("site-packages") and Path(p).is_dir()]
TRAP = "raise ImportError('a folder named mcrt shadowed the installed package')\n"


def _no_constants(name):
    raise ValueError(f"results.json holds {name}, which is not JSON")


def check_results(path: Path) -> dict:
    """Gradescope's specification of results.json, as a schema check; returns the parsed file."""
    data = json.loads(path.read_text(encoding="utf-8"), parse_constant=_no_constants)
    num = (int, float)
    assert isinstance(data, dict) and set(data) <= TOP_KEYS, set(data) - TOP_KEYS
    assert "score" in data or ("tests" in data and all("score" in t for t in data["tests"]))
    assert isinstance(data.get("score", 0), num) and not isinstance(data.get("score"), bool)
    for k, kind in (("execution_time", num), ("output", str), ("extra_data", dict), ("tests", list)):
        assert k not in data or isinstance(data[k], kind), k
    for k in ("output_format", "test_output_format", "test_name_format"):
        assert data.get(k, "text") in FORMATS, (k, data[k])
    for k in ("visibility", "stdout_visibility"):
        assert data.get(k, "visible") in VISIBILITIES, (k, data[k])
    tests = data.get("tests", [])
    for t in tests:
        assert isinstance(t, dict) and set(t) <= TEST_KEYS, set(t) - TEST_KEYS
        assert isinstance(t["name"], str) and t["name"]
        assert isinstance(t["score"], num) and isinstance(t["max_score"], num) and 0 <= t["score"] <= t["max_score"]
        assert isinstance(t.get("output", ""), str) and t.get("output_format", "text") in FORMATS
        assert t.get("status", "passed") in {"passed", "failed"} and t.get("visibility", "visible") in VISIBILITIES
        assert all(isinstance(x, str) for x in t.get("tags", []))
    if tests:
        assert abs(data["score"] - sum(t["score"] for t in tests)) < 1e-6
        assert abs(data.get("max_score", sum(t["max_score"] for t in tests)) - sum(t["max_score"] for t in tests)) < 1e-6
    return data


def _render(spp: int, seed: int, mutants=()):
    scene = load_scene()
    return render(scene, scene.settings(camera="near", width=RES, height=RES, spp=spp, max_depth=8), seed=seed,
                  progress=False, mutants=mutants)


@pytest.fixture(scope="module")
def renders():
    return {"good": _render(64, 11), "biased": _render(64, 12, mutants=("rr_no_divide",))}


@pytest.fixture(scope="module")
def tmp(tmp_path_factory):
    d = tmp_path_factory.mktemp("gradescope")
    (d / "gs16.toml").write_text(ASSIGNMENT)
    return d


def _env(root: Path) -> dict:
    env = dict(os.environ, AUTOGRADER_ROOT=str(root), MCRT_SETUP_PYTHON=sys.executable,
               MCRT_SETUP_DEPS=os.pathsep.join(DEPS))
    # This environment's libLLVM (karellen-llvm-core puts it under sys.prefix, not under the new venv's prefix).
    env["DRJIT_LIBLLVM_PATH"] = find_llvm() or ""
    env.pop("PYTHONPATH", None)
    return env


def _build(tmp: Path, mode: str) -> tuple[Path, Path]:
    """mcrt gradescope-zip, then Gradescope's image build in a simulated /autograder; returns (zip, root)."""
    zpath = tmp / f"autograder_{mode}.zip"
    r = subprocess.run([sys.executable, "-m", "mcrt.cli", "gradescope-zip", "--mode", mode, "--out", str(zpath),
                        str(tmp / "gs16.toml")], capture_output=True, text=True, timeout=600, cwd=tmp)
    assert r.returncode == 0, r.stdout + r.stderr
    root = tmp / f"autograder_{mode}"
    (root / "source").mkdir(parents=True)
    with zipfile.ZipFile(zpath) as z:
        for info in z.infolist():
            z.extract(info, root / "source")
            mode_bits = info.external_attr >> 16
            if mode_bits:
                os.chmod(root / "source" / info.filename, stat.S_IMODE(mode_bits))
    # Gradescope's working folder holds a folder named mcrt/ (an old zip's repository copy, say): a trap.
    (root / "mcrt").mkdir()
    (root / "mcrt" / "__init__.py").write_text(TRAP)
    r = subprocess.run(["bash", str(root / "source" / "setup.sh")], cwd=root, env=_env(root), capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "test mode" in r.stdout and "ready" in r.stdout
    shutil.copy2(root / "source" / "run_autograder", root / "run_autograder")  # what Gradescope's image build does
    return zpath, root


def _submit(root: Path, files: dict[str, bytes | Path]) -> dict:
    """Run the autograder on one submission, as Gradescope does; returns the checked results.json."""
    sub, res = root / "submission", root / "results"
    for d in (sub, res):
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir()
    for name, content in files.items():
        if isinstance(content, Path):
            shutil.copy(content, sub / name)
        else:
            (sub / name).write_bytes(content)
    r = subprocess.run([str(root / "run_autograder")], cwd=root, env=_env(root), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    data = check_results(res / "results.json")
    data["_stdout"] = r.stdout
    return data


@pytest.fixture(scope="module")
def image_autograder(tmp):
    return _build(tmp, "image")


@pytest.mark.long
def test_the_zip_holds_a_wheel_and_executable_scripts(image_autograder):
    zpath, root = image_autograder
    with zipfile.ZipFile(zpath) as z:
        names = set(z.namelist())
        assert {"setup.sh", "run_autograder", "assignment.toml", "mode", "requirements.lock"} <= names
        assert any(n.startswith("mcrt-") and n.endswith(".whl") for n in names)
        assert not any(n.startswith("mcrt/") for n in names)  # no repository copy to shadow the package
        for n in ("setup.sh", "run_autograder"):
            assert (z.getinfo(n).external_attr >> 16) & 0o111, n
    assert (root / "venv" / "bin" / "mcrt").exists() and (root / "cache").is_dir()


@pytest.mark.long
def test_gradescope_grades_correct_biased_and_unreadable_submissions(image_autograder, renders, tmp):
    _, root = image_autograder
    write_exr(tmp / "good.exr", renders["good"])
    write_exr(tmp / "biased.exr", renders["biased"])

    good = _submit(root, {"render.exr": tmp / "good.exr", "manifest.toml": b"spp = 64\n"})
    assert good["score"] == good["max_score"] == 100, good["output"]
    assert good["output_format"] == "md" and all(t["output_format"] == "md" for t in good["tests"])
    assert (root / "results" / "feedback.html").exists()

    bad = _submit(root, {"render.exr": tmp / "biased.exr", "manifest.toml": b"spp = 64\n"})
    assert bad["score"] < 100
    unb = next(t for t in bad["tests"] if "unbiased" in t["tags"])
    assert unb["status"] == "failed"
    # What matters reaches the student in results.json itself: the diagnosis, where, what to do.
    assert "rr\\_no\\_divide" in unb["output"] and "Closest bugs" in unb["output"], unb["output"]
    assert "per 8x8-pixel tile" in unb["output"] and "```text" in unb["output"]
    assert "**What to do:**" in unb["output"]
    assert "rr\\_no\\_divide" in bad["output"]

    junk = _submit(root, {"render.exr": b"this is not an image\n"})
    assert junk["score"] == 0
    readable = next(t for t in junk["tests"] if "readable" in t["tags"])
    assert readable["status"] == "failed" and "render.exr" in readable["output"] and "**What to do:**" in readable["output"]


@pytest.mark.long
def test_a_broken_autograder_says_so_truthfully(image_autograder, renders, tmp):
    _, root = image_autograder
    a = root / "source" / "assignment.toml"
    saved = a.read_text()
    try:
        a.write_text(saved.replace("camera = \"near\"", "camera = \"sideways\""))
        data = _submit(root, {"render.exr": tmp / "good.exr"})
    finally:
        a.write_text(saved)
    assert data["score"] == 0 and data["tests"] == []
    assert "not graded" in data["output"] and "has been told" not in data["output"]
    assert "exited with status 2" in data["_stdout"] and "sideways" in data["_stdout"]  # what staff see


@pytest.fixture(scope="module")
def code_autograder(tmp):
    return _build(tmp, "code")


@pytest.mark.long
def test_gradescope_grades_a_python_module(code_autograder, renders):
    import base64

    _, root = code_autograder
    imgs = {s: base64.b64encode(_render(64, 600 + s).mean.astype("<f4").tobytes()).decode() for s in (1, 2)}
    data = _submit(root, {"tracer.py": (GOOD + f"\nIMAGES = {imgs!r}\n").encode()})
    assert {t["tags"][0] for t in data["tests"]} >= {"sample_cosine_hemisphere", "intersect_triangle", "estimate_direct"}
    assert data["score"] == data["max_score"] == 50, [(t["name"], t["output"][:300]) for t in data["tests"]]
    crash = _submit(root, {"tracer.py": b"def sample_cosine_hemisphere(u1, u2):\n    return 1 / 0\n"})
    assert crash["score"] == 0
    t = next(t for t in crash["tests"] if t["tags"] == ["sample_cosine_hemisphere"])
    assert t["status"] == "failed" and "ZeroDivisionError" in t["output"]


# --------------------------------------------------------------------------
# A normal install grades from any folder
# --------------------------------------------------------------------------


@pytest.mark.long
def test_the_installed_wheel_grades_a_class_outside_the_checkout(image_autograder, renders, tmp):
    zpath, _ = image_autograder
    target = tmp / "site"
    with zipfile.ZipFile(zpath) as z:
        wheel = next(n for n in z.namelist() if n.endswith(".whl"))
        z.extract(wheel, tmp)
    with zipfile.ZipFile(tmp / wheel) as w:
        w.extractall(target)
    klass = tmp / "class"
    klass.mkdir()
    shutil.copy(tmp / "gs16.toml", klass / "gs16.toml")
    write_exr(klass / "alice.exr", renders["good"])
    (klass / "alice.toml").write_text("spp = 64\n")
    write_exr(klass / "bob.exr", renders["biased"])
    (klass / "bob.toml").write_text("spp = 64\n")
    (klass / "carol.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    work = tmp / "elsewhere"
    (work / "mcrt").mkdir(parents=True)
    (work / "mcrt" / "__init__.py").write_text(TRAP)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(target), *DEPS]))
    # -S: not this environment's .pth files (the editable checkout); -P: not the trap in the working folder.
    cmd = [sys.executable, "-S", "-P", "-m", "mcrt.cli", "grade", "../class", "-a", "../class/gs16.toml", "-o", "graded",
           "--cache", str(tmp / "cache_installed"), "--jobs", "2", "--quiet"]
    r = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    scores = {sid: check_results(work / "graded" / sid / "results.json")["score"] for sid in ("alice", "bob", "carol")}
    assert scores["alice"] == 100 and scores["bob"] < 100 and scores["carol"] == 0, scores
    assert (work / "graded" / "grades.csv").exists() and "shadowed" not in (work / "graded" / "grading.log").read_text()
    r = subprocess.run([sys.executable, "-S", "-P", "-c",
                        "import mcrt, mcrt.grade.batch as b, mcrt.scene as s; from mcrt.grade.assignment import load_assignment; "
                        "a = load_assignment(s.DATA_DIR / 'assignments' / 'course2023.toml'); a.load_scene(); "
                        "print(mcrt.__file__, a.scene_file, b.worker_env()['PYTHONPATH'].split(':')[0])"],
                       cwd=work, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert all(str(target) in part for part in r.stdout.split()), r.stdout  # nothing from the checkout


# --------------------------------------------------------------------------
# mcrt gradescope-zip and assignment names from a normal install
# --------------------------------------------------------------------------


def test_the_lock_pins_every_grading_dependency_at_a_version_mcrt_accepts():
    from packaging.requirements import Requirement

    from mcrt.grade.gradescope import LEFT_OUT, LOCK, grading_requirements

    assert LOCK == GRADESCOPE / "requirements.lock" or LOCK.resolve() == (GRADESCOPE / "requirements.lock").resolve()
    pins = dict(ln.split("==") for ln in LOCK.read_text().splitlines() if ln and not ln.startswith("#"))
    canon = {n.lower().replace("_", "-"): v for n, v in pins.items()}
    assert set(canon) == {n.lower().replace("_", "-") for n in grading_requirements()}, "regenerate: mcrt gradescope-zip --write-lock"
    assert not set(canon) & LEFT_OUT and {"drjit", "mitsuba", "numpy", "scipy", "scikit-image"} <= set(canon)
    from importlib import metadata

    for req in map(Requirement, metadata.requires("mcrt")):
        if not req.marker or req.marker.evaluate({"extra": ""}):
            name = req.name.lower().replace("_", "-")
            if name not in LEFT_OUT:
                assert req.specifier.contains(canon[name]), (name, canon[name], str(req.specifier))


def _mcrt(args, cwd, python=sys.executable, env=None):
    return subprocess.run([python, "-m", "mcrt.cli", *args], cwd=cwd, capture_output=True, text=True, timeout=600, env=env)


def test_assignment_names_work_in_mcrt_grade(tmp_path):
    r = _mcrt(["grade", "no_such_class", "--assignment", "course2023", "--out", "out"], tmp_path)
    assert r.returncode == 2 and "no_such_class: no such file or folder" in r.stderr, r.stderr  # the name was found
    r = _mcrt(["grade", "no_such_class", "--assignment", "course2024", "--out", "out"], tmp_path)
    assert r.returncode == 2 and "course2024: no such file (nor an assignment of the package: course2023," in r.stderr, r.stderr


@pytest.mark.parametrize("command", [["grade"], ["check"], ["gradescope-zip"], ["grade-accuracy"]])
def test_grading_help_fits_an_installed_package(command, tmp_path):
    r = _mcrt([*command, "--help"], tmp_path)
    assert r.returncode == 0
    assert "reference/" not in r.stdout and "make_zip" not in r.stdout, r.stdout


@pytest.fixture(scope="module")
def wheel_venv(tmp):
    """A fresh venv with mcrt installed from a wheel (pip install, not editable; dependencies from this environment)."""
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp / "wheel"), str(ROOT)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    venv = tmp / "wheel_venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    site_dir = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], capture_output=True,
                              text=True, check=True).stdout.strip()
    Path(site_dir, "deps.pth").write_text("".join(p + "\n" for p in DEPS))  # a path line: its .pth files are not read
    r = subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", "--no-index", next((tmp / "wheel").glob("*.whl"))],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return venv, Path(site_dir)


@pytest.mark.long
def test_gradescope_zip_from_a_wheel_install_in_another_folder(wheel_venv, tmp):
    venv, site_dir = wheel_venv
    work = tmp / "instructor"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([venv / "bin" / "mcrt", "gradescope-zip", "--mode", "code"], cwd=work, capture_output=True, text=True,
                       timeout=600, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "from the installed files" in r.stderr and str(ROOT) not in r.stdout + r.stderr
    with zipfile.ZipFile(work / "autograder.zip") as z:
        names = set(z.namelist())
        assert {"setup.sh", "run_autograder", "requirements.lock", "assignment.toml", "mode"} <= names
        assert z.read("mode") == b"code\n" and b"[code]" in z.read("assignment.toml")
        wheel = next(n for n in names if n.endswith(".whl"))
        z.extract(wheel, work)
    with zipfile.ZipFile(work / wheel) as packed, zipfile.ZipFile(next((tmp / "wheel").glob("*.whl"))) as built:
        assert set(packed.namelist()) == set(built.namelist())  # the installed files are the wheel's, no more, no less
        for n in built.namelist():
            if not n.endswith("RECORD"):
                assert packed.read(n) == built.read(n), n
    # The repacked wheel installs, and what it installs grades: the package's own assignment loads with its scene.
    venv2 = tmp / "repacked_venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv2)], check=True, timeout=300)
    py2 = venv2 / "bin" / "python"
    site2 = subprocess.run([py2, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], capture_output=True,
                           text=True, check=True).stdout.strip()
    Path(site2, "deps.pth").write_text("".join(p + "\n" for p in DEPS))
    r = subprocess.run([py2, "-m", "pip", "install", "-q", "--no-deps", "--no-index", work / wheel], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([py2, "-P", "-c", "import mcrt; from mcrt.grade.assignment import load_assignment; "
                        "a = load_assignment('course2023_code'); a.load_scene(); print(mcrt.__file__, a.path)"],
                       cwd=work, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0 and r.stdout.count(site2) == 2, r.stdout + r.stderr


@pytest.mark.long
def test_gradescope_zip_refuses_a_changed_installation(wheel_venv, tmp):
    venv, site_dir = wheel_venv
    target = site_dir / "mcrt" / "grade" / "score.py"
    saved = target.read_bytes()
    try:
        target.write_bytes(saved + b"\n# edited in place\n")
        r = subprocess.run([venv / "bin" / "mcrt", "gradescope-zip", "--out", str(tmp / "changed.zip")], cwd=tmp,
                           capture_output=True, text=True, timeout=600)
    finally:
        target.write_bytes(saved)
    assert r.returncode == 2 and "score.py: changed since mcrt was installed" in r.stderr, r.stderr
    assert not (tmp / "changed.zip").exists()
