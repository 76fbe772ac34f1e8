#!/usr/bin/env bash
# Build autograder.zip for Gradescope from a source checkout of mcrt:
#
#   reference/assignments/gradescope/make_zip.sh [--mode image|code] [--out ZIP] [ASSIGNMENT.toml [FILE...]]
#
# ASSIGNMENT.toml defaults to ../course2023.toml (../course2023_code.toml with --mode code); FILE... are shipped
# beside it (a scene file that its [scene] file names by a relative path, say). ZIP defaults to
# ./autograder.zip. The zip holds, at its root:
#   setup.sh, run_autograder   Gradescope's two scripts (this folder)
#   assignment.toml            the assignment, as given
#   mode                       "image" or "code": what run_autograder grades
#   mcrt-<version>-*.whl       the project as a wheel, built from this checkout (its working tree)
# No copy of the repository: nothing named mcrt/ can shadow the installed package.
# PYTHON (default: the checkout's .venv/bin/python, else python3) builds the wheel and checks that the assignment
# loads from inside the zip's folder, as it will on Gradescope.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
mode=image
zip_out=$PWD/autograder.zip   # not in this folder: the wheel would pack it as package data
while [ $# -gt 0 ]; do
    case $1 in
        --mode) mode=${2:?--mode needs image or code}; shift 2 ;;
        --out) zip_out=${2:?--out needs a file name}; shift 2 ;;
        -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
        --) shift; break ;;
        -*) echo "make_zip.sh: unknown option $1" >&2; exit 2 ;;
        *) break ;;
    esac
done
case $mode in image|code) ;; *) echo "make_zip.sh: --mode must be image or code, got $mode" >&2; exit 2 ;; esac
if [ ! -f "$root/pyproject.toml" ]; then
    echo "make_zip.sh: $root is not a source checkout of mcrt (no pyproject.toml): run the copy in the repository" >&2
    exit 2
fi
if [ $# -gt 0 ]; then assignment=$1; shift; elif [ "$mode" = code ]; then assignment=$here/../course2023_code.toml
else assignment=$here/../course2023.toml; fi
if [ -z "${PYTHON:-}" ]; then
    if [ -x "$root/.venv/bin/python" ]; then PYTHON=$root/.venv/bin/python; else PYTHON=python3; fi
fi
case $zip_out in /*) ;; *) zip_out=$PWD/$zip_out ;; esac

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
"$PYTHON" -m pip wheel -q --no-deps -w "$stage" "$root"
cp "$here/setup.sh" "$here/run_autograder" "$stage/"
cp "$assignment" "$stage/assignment.toml"
for f in "$@"; do cp "$f" "$stage/"; done
echo "$mode" > "$stage/mode"
chmod 755 "$stage/setup.sh" "$stage/run_autograder"

# The assignment must load where Gradescope will read it (its scene found, its [code] table there for code mode).
"$PYTHON" -P - "$stage/assignment.toml" "$mode" <<'EOF'
import sys
from mcrt.grade.assignment import AssignmentError, load_assignment
try:
    a = load_assignment(sys.argv[1])
    a.load_scene()
except AssignmentError as e:
    sys.exit(f"make_zip.sh: the assignment does not load from the zip: {e}\n"
             "  (a scene of the package is named without .toml; another scene file must be shipped: make_zip.sh A.toml SCENE.toml)")
if sys.argv[2] == "code" and a.code is None:
    sys.exit(f"make_zip.sh: --mode code, but {a.path} has no [code] table")
EOF

rm -f "$zip_out"
if command -v zip >/dev/null 2>&1; then
    (cd "$stage" && zip -qr "$zip_out" .)
else  # Python's zipfile keeps the files' permission bits too
    (cd "$stage" && "$PYTHON" -m zipfile -c "$zip_out" ./*)
fi
echo "wrote $zip_out ($mode mode, $(basename "$assignment"))"
