"""Find a libLLVM that Dr.Jit 1.5 accepts, before drjit is imported.

Dr.Jit's LLVM backend loads libLLVM at run time. Version 15 crashes on
current Dr.Jit ("Cannot select: fminimum"), so the search accepts only 16 or
newer, in this order:

1. ``DRJIT_LIBLLVM_PATH`` when the user has set it (respected as it is);
2. a system libLLVM >= 16 (the dynamic linker's cache, then /usr/lib/llvm-N);
3. the one shipped by the ``karellen-llvm-core`` wheel inside this Python
   environment (installed with mcrt on Linux; needs no root).

The first hit is written to ``DRJIT_LIBLLVM_PATH``. When there is none, the
reason is kept and :func:`require_llvm` raises it, naming what to install.
"""

from __future__ import annotations

import glob
import os
import re
import subprocess
import sys
from pathlib import Path

MIN_LLVM_MAJOR = 16

_INSTALL_HINT = (
    "install one: `pip install karellen-llvm-core` (no root needed) or "
    "`apt-get install libllvm19`, or point DRJIT_LIBLLVM_PATH at a libLLVM.so of version >= 16"
)

_problem: str | None = None


def _major(path: str) -> int | None:
    """LLVM major version from a library file name (libLLVM-19.so, libLLVM.so.19.1)."""
    name = os.path.basename(path)
    m = re.match(r"libLLVM(?:-(\d+))?\.so(?:\.(\d+))?", name)
    if not m:
        return None
    v = m.group(1) or m.group(2)
    return int(v) if v else None


def _system_candidates() -> list[str]:
    found: list[str] = []
    try:
        out = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True, timeout=10).stdout
        found += re.findall(r"=>\s*(\S*libLLVM[^\s]*\.so[^\s]*)", out)
    except (OSError, subprocess.SubprocessError):
        pass
    found += glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*")
    found += glob.glob("/usr/lib/*-linux-gnu/libLLVM*.so*")
    return found


def _wheel_candidates() -> list[str]:
    # karellen-llvm-core installs its libraries into <prefix>/lib.
    roots = {sys.prefix, sys.base_prefix, os.path.dirname(os.path.dirname(sys.executable))}
    found: list[str] = []
    for root in roots:
        found += glob.glob(os.path.join(root, "lib", "libLLVM*.so*"))
    return found


def _pick(paths: list[str]) -> tuple[str | None, list[str]]:
    """The newest acceptable library, and the too-old ones seen on the way."""
    good, old = [], []
    for p in dict.fromkeys(paths):
        major = _major(p)
        if major is None or not os.path.exists(p):
            continue
        (good if major >= MIN_LLVM_MAJOR else old).append((major, p))
    good.sort(reverse=True)
    return (good[0][1] if good else None), [p for _, p in sorted(old)]


def find_llvm() -> str | None:
    """Set ``DRJIT_LIBLLVM_PATH`` to an acceptable libLLVM; return its path or None."""
    global _problem
    _problem = None
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env:
        if not Path(env).exists():
            _problem = f"DRJIT_LIBLLVM_PATH={env} does not exist"
            return None
        return env
    path, old = _pick(_system_candidates())
    if path is None:
        path, old_wheel = _pick(_wheel_candidates())
        old += old_wheel
    if path is None:
        seen = f" (found only {', '.join(old)}, which crashes Dr.Jit)" if old else ""
        _problem = f"no libLLVM >= {MIN_LLVM_MAJOR} found{seen}; {_INSTALL_HINT}"
        return None
    os.environ["DRJIT_LIBLLVM_PATH"] = path
    return path


def require_llvm() -> None:
    """Raise a one-line error naming what to install when no libLLVM was found."""
    if _problem is not None:
        raise RuntimeError(f"Dr.Jit's LLVM backend is unusable: {_problem}")


def main() -> int:
    """Print the libLLVM that Dr.Jit will use, or why there is none (exit 1)."""
    p = find_llvm()
    print(p if p else f"mcrt: {_problem}", file=sys.stdout if p else sys.stderr)
    return 0 if p else 1
