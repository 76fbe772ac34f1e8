"""pytest plugin: compare renders in your own tests with a readable verdict and saved images.

Installed with mcrt (entry point ``pytest11``: ``mcrt = "mcrt.pytest_plugin"``),
so any test in an environment where mcrt is installed can ask for the
``assert_same_image`` fixture::

    def test_my_renderer_matches_mitsuba(assert_same_image):
        mine = my_render(spp=1024, seed=1)            # a RenderResult with per-sample variance
        ref = mcrt.reference.load_reference(None, "near", 64, 8)
        assert_same_image(mine, ref)                  # Welch tile test, Holm at FWER 0.01

When the renders differ the test fails with the report of
:func:`mcrt.stats.assert_same_image`: how many tile tests were rejected,
which tiles (with their pixel rows and columns), how large the difference is
(t, p-value, relative difference), the smallest p-value and the whole-image
difference; both means (``.npy``), the heat map of t (``.png``) and the full
comparison (``.json``) are saved in the test's own folder,
``<tmp_path>/<test name>/`` (pytest keeps the last three runs' temporary
folders), or under ``--mcrt-save-dir DIR`` when that option is given (for CI
artifacts). The fixture returns the :class:`mcrt.stats.Comparison` when the
renders agree.

Keyword arguments are those of :func:`mcrt.stats.assert_same_image`
(``alpha``, ``tile``, ``channels``, ``correction``, ``name``). Each call in
one test gets its own file names (``compare``, ``compare_2``, ...) unless
``name`` is given.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest


def pytest_addoption(parser) -> None:
    group = parser.getgroup("mcrt", "mcrt image comparison")
    group.addoption(
        "--mcrt-save-dir",
        default=None,
        metavar="DIR",
        help="save the images and reports of failing assert_same_image comparisons under DIR/<test id>/ "
             "(default: the test's tmp_path)",
    )


def _safe(nodeid: str) -> str:
    """A folder name from a test id: 'tests/test_x.py::test_y[near-8]' -> 'tests_test_x.py__test_y_near-8_'."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", nodeid).strip("_")[:200]


@pytest.fixture
def assert_same_image(request, tmp_path):
    """``assert_same_image(a, b, **kw)``: fail the test when renders ``a`` and ``b`` differ.

    Wraps :func:`mcrt.stats.assert_same_image` with ``save_dir`` set to the
    test's own folder, so a failing comparison leaves ``<name>_a.npy``,
    ``<name>_b.npy``, ``<name>_heatmap.png`` and ``<name>.json`` behind.
    """
    from mcrt.stats import assert_same_image as _assert

    root = request.config.getoption("--mcrt-save-dir", default=None)
    save_dir = Path(root) / _safe(request.node.nodeid) if root else tmp_path / _safe(request.node.name)
    used: dict[str, int] = {}

    def check(a, b, *, name: str | None = None, **kwargs):
        __tracebackhide__ = True  # the failure points at the caller's line, not into the plugin
        base = name or "compare"
        used[base] = used.get(base, 0) + 1
        stem = base if used[base] == 1 else f"{base}_{used[base]}"
        try:
            return _assert(a, b, save_dir=save_dir, name=stem, **kwargs)
        except AssertionError as e:
            # Re-raised here so that pytest shows the caller's line and the report, not the library's source.
            raise AssertionError(str(e)) from None

    check.save_dir = save_dir
    return check
