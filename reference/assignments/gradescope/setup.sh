#!/usr/bin/env bash
# Gradescope autograder image setup for `mcrt grade` (runs once, as root, when the image is built).
#
# Gradescope unpacks the autograder zip into /autograder/source. Build the zip from the repository root:
#
#     cd reference/assignments/gradescope && ./make_zip.sh        # or by hand:
#     zip -r autograder.zip setup.sh run_autograder assignment.toml mcrt/   (mcrt/ = a copy of the repository)
#
# The zip holds: setup.sh, run_autograder, assignment.toml (a copy of course2023.toml or your own), and the
# repository itself under mcrt/ (pyproject.toml, mcrt/, reference/ with the committed references).
set -euo pipefail
cd /autograder/source

# Python >= 3.11 (Gradescope's Ubuntu images ship older ones): a managed interpreter via uv.
apt-get update -q && apt-get install -y -q --no-install-recommends curl ca-certificates
curl -LsSf https://astral.sh/uv/install.sh | env UV_INSTALL_DIR=/usr/local/bin sh
uv venv --python 3.11 /autograder/venv
uv pip install --python /autograder/venv/bin/python ./mcrt

# Render the references and the bug catalogue once, into the image, so that grading one submission takes
# seconds and needs no Dr.Jit compilation (about a minute at 64x64; longer at a larger grade resolution).
/autograder/venv/bin/python -m mcrt.grade.cli grade --prepare --assignment assignment.toml --cache /autograder/cache
