"""Code mode from a normal install: mcrt built as a wheel and installed into a fresh virtual environment (issue 29).

Before, the sandbox took that environment's site-packages for the project
and bound neither it nor the environment, so every student got 0 ("No
module named 'numpy'") while the command exited 0. NumPy, Dr.Jit and
Mitsuba are copied into the new environment beside mcrt, as pip would
install them (hard links where the file system allows); mcrt's other
dependencies come from this interpreter's site-packages through a .pth file
(no download). The environment lies where any user may reach it, as an
installation does (not under pytest's private folder): there only the
sandbox, not the file modes, keeps mcrt, Dr.Jit and Mitsuba out of reach of
the fallback's unprivileged uid. Slow: it builds the wheel (pip wheel
--no-deps).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy
import pytest

import mcrt  # noqa: F401 - before Dr.Jit (it finds a usable libLLVM)
import drjit
import mitsuba
from mcrt.grade import codemode

REPO = Path(__file__).resolve().parent.parent

GRADE = """
import sys
from pathlib import Path
import mcrt
from mcrt.grade.assignment import assignment_from_dict
from mcrt.grade.batch import grade_code_class
print("mcrt from", Path(mcrt.__file__).resolve())
a = assignment_from_dict({"name": "sbx", "title": "sandbox", "scene": {"camera": "near", "width": 32, "height": 32, "spp": 64},
                          "code": {"timeout": 30, "memory_mb": 1024, "checks": {"sample_cosine_hemisphere": {"points": 10}}}})
grade_code_class(Path(sys.argv[1]), a, Path(sys.argv[2]), jobs=1)
"""

COSINE = """
import numpy as np

def sample_cosine_hemisphere(u1, u2):
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u1))], axis=1)
"""


def _link_or_copy(src, dst):
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


@pytest.fixture(scope="module")
def wheel_venv(request):
    if shutil.which("bwrap") is None and not os.environ.get("CI"):
        pytest.skip("bubblewrap is not installed (apt-get install bubblewrap)")
    # World-reachable (mode 0755 up to /), not pytest's 0700 folder: see the module's docstring.
    base = codemode._scratch_base(codemode.Isolation("fallback", ""))
    assert base is not None, "no temporary folder that any user can reach"
    tmp = Path(tempfile.mkdtemp(prefix="mcrt-wheel-", dir=base))
    os.chmod(tmp, 0o755)
    request.addfinalizer(lambda: shutil.rmtree(tmp, ignore_errors=True))
    p = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(REPO), "-w", str(tmp / "dist")],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    whl = next((tmp / "dist").glob("mcrt-*.whl"))
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    p = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps", "--no-index", str(whl)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    site = Path(subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    assert (site / "mcrt" / "grade" / "_sandbox.py").is_file()
    # NumPy, Dr.Jit and Mitsuba beside mcrt, as `pip install mcrt-*.whl` would put them; the rest from here.
    for mod in (numpy, drjit, mitsuba):
        src = Path(mod.__file__).resolve().parent
        for item in [src, src.with_name(src.name + ".libs"), *src.parent.glob(f"{src.name}-*.dist-info")]:
            if item.exists():
                shutil.copytree(item, site / item.name, copy_function=_link_or_copy)
    deps = [p for p in sys.path if p.endswith(("site-packages", "dist-packages")) and os.path.isdir(p)]
    (site / "zz_deps.pth").write_text("\n".join(deps) + "\n")
    return py


PEEK = """
import glob, os, sys

def _readable(path):
    try:
        return bool(open(path, "rb").read(1))
    except OSError:
        return False

def sample_cosine_hemisphere(u1, u2):
    # lib* takes in a venv's lib64 -> lib: a path to the same files through a link.
    for site in {p for p in sys.path if p.endswith("site-packages")} | set(glob.glob(sys.prefix + "/lib*/python3*/site-packages")):
        for name in ("mcrt/__init__.py", "mcrt/grade/codemode.py", "mitsuba/__init__.py", "drjit/__init__.py"):
            if _readable(os.path.join(site, name)):
                raise RuntimeError(f"read {site}/{name}")
    sys.meta_path[:] = [m for m in sys.meta_path if getattr(m, "__name__", "") != "_Hidden"]
    for name, attr in (("mitsuba", "set_variant"), ("drjit", "llvm"), ("mcrt", "render")):
        try:
            mod = __import__(name)
        except Exception:
            continue
        if hasattr(mod, attr):
            raise RuntimeError(f"imported {name} from {getattr(mod, '__file__', None)}")
    return _cosine(u1, u2)
"""


@pytest.mark.parametrize("sandbox", ["bwrap", "fallback"])
def test_a_wheel_in_a_venv_grades_a_correct_module_to_full_marks(wheel_venv, tmp_path, sandbox):
    """... and the installed mcrt's files (now bound with its site-packages), Mitsuba's and Dr.Jit's stay unreadable."""
    (tmp_path / "class").mkdir()
    (tmp_path / "class" / "good.py").write_text(textwrap.dedent(COSINE))
    (tmp_path / "class" / "peek.py").write_text(textwrap.dedent(COSINE).replace("def sample_cosine_hemisphere", "def _cosine")
                                                + textwrap.dedent(PEEK))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "MCRT_SANDBOX")}
    env["MCRT_SANDBOX"] = sandbox
    p = subprocess.run([str(wheel_venv), "-c", GRADE, str(tmp_path / "class"), str(tmp_path / "out")], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    assert f"mcrt from {wheel_venv.parent.parent}" in p.stdout, p.stdout  # the installed package, not the checkout
    for sid in ("good", "peek"):
        res = json.loads((tmp_path / "out" / sid / "results.json").read_text())
        assert res["score"] == 10, json.dumps(res)[:3000]
