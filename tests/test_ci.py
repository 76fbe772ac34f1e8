"""``.ci/run`` installs the tools the tests need, recognising ImageMagick by what it is, not by its name.

The script is copied into a temporary checkout whose ``./dev`` is a stub that records the test command; ``apt-get``,
``id`` and the tools are stubs on PATH, so nothing is installed and no test suite runs.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# What machines of this kind have as /usr/local/bin/convert.
STAND_IN = ("#!/bin/sh\necho 'convert: ImageMagick is not installed here, and this stand-in only prints a PNG: "
            "convert FILE.png ppm:-. For anything else: apt-get install imagemagick' >&2\nexit 1\n")
IMAGEMAGICK = "#!/bin/sh\necho 'Version: ImageMagick 6.9.11-60 Q16 x86_64 2021-01-25 https://imagemagick.org'\n"


def _stub(d: Path, name: str, text: str) -> None:
    (d / name).write_text(text)
    (d / name).chmod(0o755)


def _run_ci(tmp_path: Path, convert: str) -> tuple[subprocess.CompletedProcess, str]:
    checkout = tmp_path / "checkout"
    (checkout / ".ci").mkdir(parents=True)
    shutil.copy2(ROOT / ".ci" / "run", checkout / ".ci" / "run")
    log = tmp_path / "calls.log"
    _stub(checkout, "dev", f"#!/bin/sh\necho \"dev $* (MCRT_SLOW=$MCRT_SLOW CI=$CI)\" >> {log}\n")
    stubs = tmp_path / "bin"
    stubs.mkdir()
    _stub(stubs, "apt-get", f"#!/bin/sh\necho \"apt-get $*\" >> {log}\n")
    _stub(stubs, "id", "#!/bin/sh\necho 0\n")
    for tool in ("chromium", "bwrap", "mmdebstrap"):
        _stub(stubs, tool, "#!/bin/sh\nexit 0\n")
    _stub(stubs, "convert", convert)
    env = {"PATH": f"{stubs}:/usr/bin:/bin", "HOME": str(tmp_path)}
    r = subprocess.run(["bash", str(checkout / ".ci" / "run")], cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=120)
    return r, log.read_text() if log.exists() else ""


def test_ci_installs_imagemagick_when_convert_is_a_stand_in(tmp_path):
    r, calls = _run_ci(tmp_path, STAND_IN)
    assert "apt-get install -y -qq imagemagick" in calls, (calls, r.stderr)
    assert "dev test -q" in calls and r.returncode == 0, r.stderr


def test_ci_keeps_a_real_imagemagick_and_runs_the_slow_tests(tmp_path):
    r, calls = _run_ci(tmp_path, IMAGEMAGICK)
    assert "imagemagick" not in calls and "dev test -q (MCRT_SLOW=1 CI=1)" in calls, calls
    assert r.returncode == 0, r.stderr
