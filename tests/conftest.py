"""Shared fixtures and the ``long`` marker.

``grade_cache``: one cache of the grading contexts' renders for the whole run (``$MCRT_CACHE/grade`` when that is
set). Each render is keyed by the scene's content hash, its settings, the mutant and mcrt's source hash
(mcrt.grade.expected), as in the production cache, so the modules that prepare the same assignment prepare it from
nothing only once, and different assignments never read each other's renders.

``long``: an end-to-end check of minutes (an 800 x 800 hand-in graded from an empty cache, a Gradescope zip built and
run in a simulated /autograder, a Debian root built). It runs when ``MCRT_SLOW=1`` (``.ci/run`` sets it) and is
skipped otherwise, so that ``./dev test`` stays short.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def grade_cache(tmp_path_factory) -> Path:
    env = os.environ.get("MCRT_CACHE")
    return Path(env) / "grade" if env else tmp_path_factory.mktemp("grade_cache")


def pytest_collection_modifyitems(config, items):
    if os.environ.get("MCRT_SLOW"):
        return
    skip = pytest.mark.skip(reason="an end-to-end check of minutes: set MCRT_SLOW=1 (.ci/run does)")
    for item in items:
        if item.get_closest_marker("long"):
            item.add_marker(skip)
