#!/usr/bin/env bash
# Gradescope autograder image setup for `mcrt grade` (runs once, as root, when the image is built).
#
# Gradescope unpacks autograder.zip (built by make_zip.sh: setup.sh, run_autograder, assignment.toml, mode and
# the mcrt wheel) into /autograder/source. This script installs with the OS package manager and pip only:
#   1. a Python >= 3.11: the newest python3.N on PATH, else Ubuntu's python3.11/python3.12 packages (apt-get);
#   2. a virtual environment /autograder/venv with the wheel and its dependencies from PyPI (pip);
#   3. the references and the bug catalogue, rendered once into /autograder/cache (`mcrt grade --prepare`),
#      so that grading one submission takes seconds.
#
# Settings (environment variables; Gradescope sets none of them, so the defaults are what runs there):
#   AUTOGRADER_ROOT=/autograder   where source/, venv/, cache/ live (a simulated layout in tests)
#   MCRT_SETUP_PYTHON=PATH        the interpreter to build the venv from (default: found as in step 1)
#   MCRT_SETUP_DEPS=SITE          test mode, explicit: no apt-get and no download; the venv takes the dependencies
#                                 from the site-packages folder SITE (a .pth line) and pip installs only the wheel
#                                 (--no-deps --no-index)
set -euo pipefail
root=${AUTOGRADER_ROOT:-/autograder}
src=$root/source
venv=$root/venv
cd "$src"
say() { echo "setup.sh: $*"; }

py_ok() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 11))' >/dev/null 2>&1; }

find_python() {
    local c
    for c in python3.13 python3.12 python3.11 python3; do
        if command -v "$c" >/dev/null 2>&1 && py_ok "$(command -v "$c")"; then command -v "$c"; return 0; fi
    done
    return 1
}

py=${MCRT_SETUP_PYTHON:-}
if [ -n "$py" ]; then
    py_ok "$py" || { say "MCRT_SETUP_PYTHON=$py is not a Python >= 3.11" >&2; exit 1; }
    say "using $py (MCRT_SETUP_PYTHON)"
elif py=$(find_python); then
    say "using $py ($("$py" -V 2>&1), already installed)"
elif [ -n "${MCRT_SETUP_DEPS:-}" ]; then
    say "test mode (MCRT_SETUP_DEPS) installs nothing with apt-get, and no Python >= 3.11 is on PATH" >&2
    exit 1
else
    say "installing Python with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q
    # Ubuntu 24.04: python3 is 3.12; 22.04: python3.11 from jammy-updates (universe).
    for v in 3.12 3.11; do
        if apt-get install -y -q --no-install-recommends "python$v" "python$v-venv"; then break; fi
    done
    py=$(find_python) || { say "no Python >= 3.11 could be installed with apt-get" >&2; exit 1; }
    say "using $py ($("$py" -V 2>&1))"
fi

wheel=$(ls "$src"/mcrt-*.whl 2>/dev/null | head -n 1 || true)
[ -n "$wheel" ] || { say "no mcrt-*.whl in $src: build the zip with make_zip.sh" >&2; exit 1; }
# Debian and Ubuntu ship venv's ensurepip in a package of its own (python3.N-venv).
if ! { rm -rf "$venv" && "$py" -m venv "$venv"; }; then
    [ -z "${MCRT_SETUP_DEPS:-}" ] || { say "$py cannot make a virtual environment (test mode installs nothing)" >&2; exit 1; }
    v=$("$py" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
    say "installing python$v-venv with apt-get"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "python$v-venv" ||
        { apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "python$v-venv"; }
    rm -rf "$venv" && "$py" -m venv "$venv"
fi
if [ -n "${MCRT_SETUP_DEPS:-}" ]; then
    say "test mode: dependencies from $MCRT_SETUP_DEPS, nothing downloaded"
    site=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    echo "$MCRT_SETUP_DEPS" > "$site/mcrt-setup-deps.pth"
    "$venv/bin/python" -m pip install -q --no-deps --no-index "$wheel"
else
    "$venv/bin/python" -m pip install -q --upgrade pip
    "$venv/bin/python" -m pip install -q "$wheel"
fi
# The installed package, not a folder of the working directory (-P), is what grades.
say "installed: $("$venv/bin/python" -P -c 'import mcrt; print("mcrt", mcrt.__version__, "in", mcrt.__file__)')"

# Render the references and the bug catalogue once, into the image (about a minute at 64x64).
"$venv/bin/mcrt" grade --prepare --assignment "$src/assignment.toml" --cache "$root/cache"
say "ready"
