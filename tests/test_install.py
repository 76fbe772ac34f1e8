"""A normal (non-editable) install works from any folder: the wheel ships the code, the plugins and the ground truth.

The wheel is built from this checkout and unpacked into a fresh folder; a
Python that does not read this environment's .pth files (``-S``, so the
editable install of the checkout is not on the path) imports mcrt from there
and takes its dependencies from this environment's site-packages.
"""

from __future__ import annotations

import os
import site
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("install")
    # Built as pip builds any project: in an isolated environment with the build backend pyproject.toml asks for.
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp / "dist"), str(ROOT)],
                   check=True, capture_output=True)
    wheel = next((tmp / "dist").glob("mcrt-*.whl"))
    target = tmp / "site"
    with zipfile.ZipFile(wheel) as z:
        z.extractall(target)
    return wheel, target


def _run(target: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(target), *site.getsitepackages()]))
    return subprocess.run([sys.executable, "-S", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_the_wheel_holds_the_plugins_and_the_ground_truth(installed):
    wheel, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for need in ("mcrt/estimator.py", "mcrt/plugins/host.py", "mcrt/data/manifest.json", "mcrt/data/scenes/canonical.toml",
                 "mcrt/data/scenes/hard/light_low.toml", "mcrt/data/canonical_near_64x64_d8.exr",
                 "mcrt/data/assignments/course2023.toml"):
        assert need in names, need


def test_the_installed_package_renders_and_compares_from_another_folder(installed, tmp_path):
    _, target = installed
    r = _run(target, tmp_path, "-c", "import mcrt, mcrt.scene as s, mcrt.plugins as p; print(mcrt.__file__, s.DATA_DIR, p.__file__)")
    assert r.returncode == 0, r.stderr
    assert all(str(target) in part for part in r.stdout.split()), r.stdout  # nothing from the checkout
    for args in (["--help"], ["scene"], ["reference", "list"], ["mutants"], ["mitsuba-suite", "--help"]):
        r = _run(target, tmp_path, "-m", "mcrt.cli", *args)
        assert r.returncode == 0, (args, r.stderr[-2000:])
    r = _run(target, tmp_path, "-m", "mcrt.cli", "render", "--res", "8", "--spp", "4", "--seed", "1", "-o", "a.exr")
    assert r.returncode == 0, r.stderr[-2000:]
    r = _run(target, tmp_path, "-m", "mcrt.cli", "render", "--renderer", "plugin", "--res", "8", "--spp", "4", "--seed", "2", "-o", "b.exr")
    assert r.returncode == 0, r.stderr[-2000:]
    r = _run(target, tmp_path, "-m", "mcrt.cli", "compare", "a.exr", "b.exr")
    assert r.returncode in (0, 1) and ("consistent" in r.stdout or "DIFFERENT" in r.stdout), r.stdout + r.stderr
