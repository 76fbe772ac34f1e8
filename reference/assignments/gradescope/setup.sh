#!/usr/bin/env bash
# Gradescope autograder image setup for `mcrt grade` (runs once, as root, when the image is built).
#
# Gradescope unpacks autograder.zip (built by `mcrt gradescope-zip`: setup.sh, run_autograder, requirements.lock,
# assignment.toml, mode and the mcrt wheel) into /autograder/source. This script installs with the OS package
# manager and pip only:
#   1. the OS libraries the wheels load (libatomic1: Dr.Jit's LLVM backend), bubblewrap (the code-mode sandbox)
#      and, when no python3.N >= 3.11 is on PATH, Ubuntu's python3.12 or python3.11 with its -venv package
#      (apt-get, no recommended packages; apt's lists and cache removed afterwards);
#   2. a virtual environment /autograder/venv with exactly the versions of requirements.lock and the wheel
#      (pip --no-deps --no-cache-dir: nothing resolved anew, no pip cache left in the image);
#   3. checks that grading's libraries import, and that an unprivileged uid (nobody, 65534: code mode runs student
#      code as a uid other than root) can import numpy and mcrt from the venv: fatal in code mode (but in test mode);
#   4. the references and the bug catalogue, rendered once into /autograder/cache (`mcrt grade --prepare`),
#      so that grading one submission takes seconds.
#
# Settings (environment variables; Gradescope sets none of them, so the defaults are what runs there):
#   AUTOGRADER_ROOT=/autograder   where source/, venv/, cache/ live (a simulated layout in tests)
#   MCRT_SETUP_PYTHON=PATH        the interpreter to build the venv from (default: found as in step 1)
#   MCRT_SETUP_DEPS=SITE[:SITE]   test mode, explicit: no apt-get and no download; the venv takes the dependencies
#                                 from the site-packages folders SITE (.pth lines) and pip installs only the wheel
#                                 (--no-deps --no-index)
#   PIP_CERT, PIP_INDEX_URL, ...  pip's own settings, passed on
set -euo pipefail
umask 022   # the venv and the cache readable by the unprivileged uid that runs student code
root=${AUTOGRADER_ROOT:-/autograder}
src=$root/source
venv=$root/venv
cd "$src"
say() { echo "setup.sh: $*"; }
test_mode=${MCRT_SETUP_DEPS:+1}
mode=$(cat "$src/mode" 2>/dev/null || echo image)
export DEBIAN_FRONTEND=noninteractive

# OS packages grading needs: libatomic1 (drjit's libdrjit-core loads libatomic.so.1; without it the import fails
# with "NameError: name '_drjit_ext' is not defined"), bubblewrap (code mode's sandbox, where the container
# allows namespaces).
OS_PACKAGES=(libatomic1 bubblewrap)

apt_updated=
apt_install() {
    [ -n "$apt_updated" ] || { apt-get update -q; apt_updated=1; }
    apt-get install -y -q --no-install-recommends "$@"
}
apt_clean() {  # apt's package lists and downloaded packages have no use in the image
    [ -z "$apt_updated" ] || { apt-get clean; rm -rf /var/lib/apt/lists/*; }
}
trap apt_clean EXIT

py_ok() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 11))' >/dev/null 2>&1; }

find_python() {
    local c
    for c in python3.13 python3.12 python3.11 python3; do
        if command -v "$c" >/dev/null 2>&1 && py_ok "$(command -v "$c")"; then command -v "$c"; return 0; fi
    done
    return 1
}

if [ -z "$test_mode" ]; then
    missing=()
    for p in "${OS_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then say "installing ${missing[*]} with apt-get"; apt_install "${missing[@]}"; fi
fi

py=${MCRT_SETUP_PYTHON:-}
if [ -n "$py" ]; then
    py_ok "$py" || { say "MCRT_SETUP_PYTHON=$py is not a Python >= 3.11" >&2; exit 1; }
    say "using $py (MCRT_SETUP_PYTHON)"
elif py=$(find_python); then
    say "using $py ($("$py" -V 2>&1), already installed)"
elif [ -n "$test_mode" ]; then
    say "test mode (MCRT_SETUP_DEPS) installs nothing with apt-get, and no Python >= 3.11 is on PATH" >&2
    exit 1
else
    say "installing Python with apt-get"
    # Ubuntu 24.04: python3 is 3.12; 22.04: python3.11 from jammy-updates (universe); Debian 12: 3.11.
    for v in 3.12 3.11; do
        if apt_install "python$v" "python$v-venv"; then break; fi
    done
    py=$(find_python) || { say "no Python >= 3.11 could be installed with apt-get" >&2; exit 1; }
    say "using $py ($("$py" -V 2>&1))"
fi

wheel=$(ls "$src"/mcrt-*.whl 2>/dev/null | head -n 1 || true)
[ -n "$wheel" ] || { say "no mcrt-*.whl in $src: build the zip with mcrt gradescope-zip" >&2; exit 1; }
[ -n "$test_mode" ] || [ -f "$src/requirements.lock" ] ||
    { say "no requirements.lock in $src: build the zip with mcrt gradescope-zip" >&2; exit 1; }
# Debian and Ubuntu ship venv's ensurepip in a package of its own (python3.N-venv).
if ! { rm -rf "$venv" && "$py" -m venv "$venv"; } >/dev/null 2>&1; then
    [ -z "$test_mode" ] || { say "$py cannot make a virtual environment (test mode installs nothing)" >&2; exit 1; }
    v=$("$py" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
    say "installing python$v-venv with apt-get"
    apt_install "python$v-venv"
    rm -rf "$venv" && "$py" -m venv "$venv"
fi
apt_clean
if [ -n "$test_mode" ]; then
    say "test mode: dependencies from $MCRT_SETUP_DEPS, nothing downloaded"
    site=$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    tr ':' '\n' <<< "$MCRT_SETUP_DEPS" > "$site/mcrt-setup-deps.pth"
    "$venv/bin/python" -m pip install -q --no-deps --no-index "$wheel"
else
    # Exactly the pinned versions, and only them: --no-deps leaves out what grading never imports (matplotlib,
    # dask), which the wheel's metadata still names.
    say "installing $(grep -c '==' "$src/requirements.lock") pinned packages (requirements.lock) and $(basename "$wheel")"
    "$venv/bin/python" -m pip install -q --no-cache-dir --no-deps --disable-pip-version-check -r "$src/requirements.lock"
    "$venv/bin/python" -m pip install -q --no-cache-dir --no-deps --disable-pip-version-check "$wheel"
fi
# The installed package, not a folder of the working directory (-P), is what grades; every library grading
# loads is imported now, so that a missing OS library stops the build here, by name.
say "installed: $("$venv/bin/python" -P -c 'import mcrt; print("mcrt", mcrt.__version__, "in", mcrt.__file__)')"
"$venv/bin/python" -P -c 'import mcrt.llvm, drjit, mitsuba, numpy, scipy.stats, skimage.metrics, OpenEXR, png, PIL.Image, flip_evaluator'

# Code mode runs student code as a uid other than root (by number: no user account is needed), with numpy from
# this venv: the venv must be open to others. uid 65534 (nobody) stands for any such uid.
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null 2>&1; then
    if setpriv --reuid=65534 --regid=65534 --clear-groups -- "$venv/bin/python" -P -c 'import numpy, mcrt' \
            </dev/null >/dev/null 2>&1; then
        say "an unprivileged uid (65534) can run the venv's Python and import numpy and mcrt"
    elif [ "$mode" = code ] && [ -z "$test_mode" ]; then  # a test's simulated layout may sit in a private folder
        say "uid 65534 cannot import numpy and mcrt from $venv (is a folder above it closed to others?); code mode needs it" >&2
        exit 1
    else
        say "note: uid 65534 cannot import numpy and mcrt from $venv (code mode needs it)"
    fi
fi
command -v bwrap >/dev/null 2>&1 && say "bubblewrap: $(bwrap --version)"

# Render the references and the bug catalogue once, into the image (about a minute at 64x64).
"$venv/bin/mcrt" grade --prepare --assignment "$src/assignment.toml" --cache "$root/cache"
say "ready"
