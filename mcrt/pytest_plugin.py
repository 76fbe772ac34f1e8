"""pytest plugin: compare renders in your own tests with a readable verdict and saved images.

Installed with mcrt (entry point ``pytest11``: ``mcrt = "mcrt.pytest_plugin"``),
so any test in an environment where mcrt is installed can ask for the
``assert_same_image`` fixture::

    def test_my_renderer_matches_mitsuba(assert_same_image):
        mean, var = my_render(spp=1024, seed=1)       # NumPy (H, W, 3): mean and per-sample variance
        ref = mcrt.groundtruth.load_reference(None, "near", 64, 8)
        assert_same_image(mean, ref, variance_a=var, spp_a=1024, policy="reference-floor")

Each side is a RenderResult, an image file (an EXR with its variance,
Mitsuba's ``moment`` integrator's output) or a NumPy mean with
``variance_a``/``spp_a`` (``variance_b``/``spp_b``) alongside. The policy
is explicit: ``'independent'`` (the default) for two independent renders
(two integrators, two seeds), ``'reference-floor'`` for a render against a
high-spp reference of the same estimator, such as the committed Mitsuba
references (without the floor, correct low-spp renders that miss rare
bright paths are rejected; see :mod:`mcrt.stats.policy`). Renders whose
headers record different resolutions, cameras, scene hashes or max depths
are refused (:func:`mcrt.compare.check_headers`; ``allow_mismatch=`` names
the fields to compare anyway).

When the renders differ the test fails with the report of
:func:`assert_same_image`: how many tile tests were rejected, which tiles
(with their pixel rows and columns), how large the difference is (t,
p-value, relative difference), the smallest p-value and the whole-image
difference; both means (``.npy``), the heat map of t (``.png``) and the full
comparison (``.json``) are saved in the test's own folder,
``<tmp_path>/<test name>/`` (pytest keeps the last three runs' temporary
folders), or under ``--mcrt-save-dir DIR`` when that option is given (for CI
artifacts). The fixture returns the :class:`mcrt.stats.Comparison` when the
renders agree.

Keyword arguments are those of :func:`assert_same_image` (``policy``,
``variance_a``, ``spp_a``, ``variance_b``, ``spp_b``, ``allow_mismatch``,
``alpha``, ``tile``, ``channels``, ``correction``, ``name``). Each call in
one test gets its own file names (``compare``, ``compare_2``, ...) unless
``name`` is given.

The plugin is loaded by every pytest run in the environment, so NumPy and
:mod:`mcrt.stats` are imported only when a comparison runs.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from mcrt.film import RenderResult
    from mcrt.stats import Comparison

__all__ = ["assert_same_image"]


def assert_same_image(
    a,
    b,
    *,
    policy: str = "independent",
    variance_a=None,
    spp_a: int | None = None,
    variance_b=None,
    spp_b: int | None = None,
    allow_mismatch=(),
    save_dir=None,
    name: str = "compare",
    **options,
) -> Comparison:
    """Assert that two renders agree under :func:`mcrt.stats.compare`.

    ``a`` is the render under test and ``b`` the other one (the high-spp
    reference under ``policy='reference-floor'``; see
    :mod:`mcrt.stats.policy` for which policy to use when). Each is a
    RenderResult, an image file or a NumPy mean with its per-sample variance
    and spp given alongside (:func:`mcrt.compare.as_result`). Returns the
    :class:`~mcrt.stats.Comparison` when they agree. Otherwise raises
    ``AssertionError`` with the multi-line report of
    :func:`mcrt.compare.report_lines`. ``options`` (``alpha``, ``tile``,
    ``channels``, ``correction``) are those of :func:`mcrt.stats.compare`.
    With ``save_dir`` a failure also saves the two means as
    ``{name}_a.npy`` / ``{name}_b.npy``, the heat map ``{name}_heatmap.png``
    and the report ``{name}.json`` there.
    :class:`~mcrt.stats.StatsError` (unusable inputs: a bare array without
    its variance or spp, headers that differ,
    :class:`mcrt.compare.HeaderMismatch`) and ``ValueError`` (invalid
    options) propagate unchanged.
    """
    __tracebackhide__ = True
    from mcrt.compare import as_result, check_headers, report_lines
    from mcrt.stats import compare

    a = as_result(a, name="A", variance=variance_a, spp=spp_a)
    b = as_result(b, name="B", variance=variance_b, spp=spp_b)
    check_headers(a, b, allow=allow_mismatch)
    c = compare(a, b, policy=policy, **options)
    if c.passed:
        return c
    lines = report_lines(c)
    lines[0] = "renders differ: " + lines[0]
    if save_dir is not None:
        _save(c, a, b, Path(save_dir), name)
        lines.append(f"saved means, heat map and report to {save_dir}/{name}_*")
    raise AssertionError("\n".join(lines))


def _save(c: Comparison, a: RenderResult, b: RenderResult, d: Path, name: str) -> None:
    """The failure's files: both means (.npy), the heat map (.png, about 256 pixels wide) and the report (.json)."""
    import numpy as np

    from mcrt.compare import write_heatmap, write_json

    d.mkdir(parents=True, exist_ok=True)
    np.save(d / f"{name}_a.npy", a.mean)
    np.save(d / f"{name}_b.npy", b.mean)
    write_heatmap(c, d / f"{name}_heatmap.png", scale=max(1, 256 // max(c.shape[1], 1)))
    write_json(c, d / f"{name}.json")


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


@pytest.fixture(name="assert_same_image")
def _assert_same_image_fixture(request, tmp_path):
    """``assert_same_image(a, b, **kw)``: fail the test when renders ``a`` and ``b`` differ.

    Wraps :func:`assert_same_image` with ``save_dir`` set to the test's own
    folder, so a failing comparison leaves ``<name>_a.npy``,
    ``<name>_b.npy``, ``<name>_heatmap.png`` and ``<name>.json`` behind.
    """
    root = request.config.getoption("--mcrt-save-dir", default=None)
    save_dir = Path(root) / _safe(request.node.nodeid) if root else tmp_path / _safe(request.node.name)
    used: dict[str, int] = {}

    def check(a, b, *, name: str | None = None, **kwargs):
        __tracebackhide__ = True  # the failure points at the caller's line, not into the plugin
        base = name or "compare"
        used[base] = used.get(base, 0) + 1
        stem = base if used[base] == 1 else f"{base}_{used[base]}"
        try:
            return assert_same_image(a, b, save_dir=save_dir, name=stem, **kwargs)
        except AssertionError as e:
            # Re-raised here so that pytest shows the caller's line and the report, not the library's source.
            raise AssertionError(str(e)) from None

    check.save_dir = save_dir
    return check
