#!/usr/bin/env bash
# Build autograder.zip for Gradescope from this repository: setup.sh, run_autograder, the assignment,
# and a copy of the repository (tracked files only) under mcrt/.
#   ./make_zip.sh [assignment.toml]     (default: ../course2023.toml)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(git -C "$here" rev-parse --show-toplevel)
assignment=${1:-$here/../course2023.toml}
stage=$(mktemp -d)
mkdir "$stage/mcrt"
git -C "$root" archive HEAD | tar -x -C "$stage/mcrt"
cp "$here/setup.sh" "$here/run_autograder" "$stage/"
cp "$assignment" "$stage/assignment.toml"
chmod +x "$stage/setup.sh" "$stage/run_autograder"
(cd "$stage" && zip -qr "$here/autograder.zip" .)
rm -rf "$stage"
echo "wrote $here/autograder.zip"
