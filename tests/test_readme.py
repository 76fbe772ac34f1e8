"""The README's examples run as written: every ```python block, and the shell blocks tagged ```sh test.

Each block runs in a fresh temporary folder (the shell blocks with this
environment's ``mcrt`` first on PATH), so the files one command writes are
the ones the next one reads, as for a reader typing them in order.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```", re.S | re.M)


def blocks(tag: str) -> list[str]:
    """The README's fenced blocks whose info string is exactly ``tag``."""
    return [body for info, body in FENCE.findall((ROOT / "README.md").read_text()) if info.strip() == tag]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    return env


def test_the_readme_has_the_examples_the_test_runs():
    assert len(blocks("python")) >= 3 and len(blocks("sh test")) >= 2
    # The command-line comparison compares two renders of one camera (not near against far).
    first = blocks("sh test")[0]
    cameras = re.findall(r"--camera (\w+)", first)
    assert len(cameras) == 2 and len(set(cameras)) == 1, first


@pytest.mark.parametrize("k", range(len(blocks("python"))))
def test_python_example(k, tmp_path):
    code = blocks("python")[k]
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=_env(), capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, f"README python block {k} failed:\n{code}\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}"


@pytest.mark.parametrize("k", range(len(blocks("sh test"))))
def test_shell_example(k, tmp_path):
    for line in blocks("sh test")[k].splitlines():
        command = line.split("  #", 1)[0].strip()
        if not command:
            continue
        r = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, f"README command failed ({r.returncode}): {command}\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}"
