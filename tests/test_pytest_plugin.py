"""The pytest plugin (mcrt.pytest_plugin): the ``assert_same_image`` fixture in someone else's tests.

The inner test files run in a fresh pytest (pytester) that finds the plugin
through its ``pytest11`` entry point, as a renderer author's project would.
The renders are synthetic (means and variances drawn with NumPy), so no
rendering is needed.
"""

from __future__ import annotations

import json

pytest_plugins = ["pytester"]

# Helpers placed in the inner test files: two 32x32 renders with 4096 spp,
# per-sample variance 1; 'shifted' is 20 % brighter in tile (1, 2) (rows 8-15, cols 16-23).
HELPERS = '''
import numpy as np
from mcrt.film import RenderResult

def render(seed, shifted=False):
    rng = np.random.default_rng(seed)
    spp = 4096
    mean = 0.5 + rng.normal(0.0, 1.0 / np.sqrt(spp), (32, 32, 3))
    if shifted:
        mean[8:16, 16:24] *= 1.2
    return RenderResult(mean=mean.astype(np.float32), variance=np.ones((32, 32, 3), np.float32),
                        spp=spp, seed=seed, max_depth=8, renderer="synthetic")
'''


def test_failure_is_readable_and_saves_the_images(pytester):
    pytester.makepyfile(HELPERS + '''
def test_differ(assert_same_image):
    assert_same_image(render(1, shifted=True), render(2))
''')
    save = pytester.path / "saved"
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", f"--mcrt-save-dir={save}")
    result.assert_outcomes(failed=1)
    out = result.stdout.str()
    # How many tiles, where (tile and pixel ranges), how large, p-value, where the files are.
    result.stdout.fnmatch_lines([
        "*renders differ: DIFFERENT: 3 of 48 tile tests rejected at FWER 0.01 (Holm, 8x8 tiles, rgb)*",
        "*tile (1,2) ? *rows 8-15 cols 16-23*t=+*p=*(+18.* % symmetric)*",
        "*largest effect: +18.* % (symmetric) at tile (1,2)*",
        "*whole-image mean, symmetric relative difference (A-B)/mean(|A|,|B|): R +*",
        "*saved means, heat map and report to *",
    ])
    assert "test_differ(assert_same_image)" in out  # the traceback points at the caller's line...
    assert "def assert_same_image(" not in out  # ...and does not list the library's source
    folder = next(save.iterdir())
    assert "test_differ" in folder.name
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["compare.json", "compare_a.npy", "compare_b.npy", "compare_heatmap.png"]
    report = json.loads((folder / "compare.json").read_text())
    assert report["n_rejected"] == 3 and not report["passed"]
    assert {tuple(t["box"]) for t in report["failing_tiles"]} == {(8, 16, 16, 24)}


def test_fixture_found_by_entry_point_saves_per_test_and_passes_options(pytester):
    pytester.makepyfile(HELPERS + '''
import pytest

def test_agree(assert_same_image):
    c = assert_same_image(render(1), render(2))
    assert c.passed and c.n_tests == 48
    assert not assert_same_image.save_dir.exists()  # nothing saved when the renders agree

def test_two_failures_in_one_test(assert_same_image, tmp_path):
    a, b = render(1, shifted=True), render(2)
    for _ in range(2):
        with pytest.raises(AssertionError, match="renders differ"):
            assert_same_image(a, b, tile=16)
    assert assert_same_image.save_dir.parent == tmp_path
    names = sorted(p.name for p in assert_same_image.save_dir.iterdir())
    assert names == ["compare.json", "compare_2.json", "compare_2_a.npy", "compare_2_b.npy", "compare_2_heatmap.png",
                     "compare_a.npy", "compare_b.npy", "compare_heatmap.png"]

def test_options_pass_through(assert_same_image):
    c = assert_same_image(render(1), render(2), alpha=0.05, tile=4, channels="luminance", correction="bh")
    assert (c.alpha, c.tile, c.channels, c.correction, c.n_tests) == (0.05, 4, "luminance", "bh", 64)
    assert c.policy == "independent"
    assert assert_same_image(render(1), render(2), policy="reference-floor").policy == "reference-floor"
''')
    # No -p option: the plugin must come from the installed pytest11 entry point.
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=3)


def test_arrays_files_and_headers(pytester):
    """NumPy means with variance and spp alongside, EXR files, a clear error without them, refused headers."""
    pytester.makepyfile(HELPERS + '''
import dataclasses
import pytest
from mcrt.compare import HeaderMismatch, image
from mcrt.image_files import write_exr
from mcrt.stats import StatsError

def test_arrays(assert_same_image):
    a, b = render(1), render(2)
    c = assert_same_image(a.mean, b.mean, variance_a=a.variance, spp_a=a.spp, variance_b=b.variance, spp_b=b.spp)
    assert c.passed
    assert assert_same_image(image(a.mean, a.variance, a.spp), b).passed
    with pytest.raises(StatsError, match="image A is a bare array: give its per-sample variance and spp"):
        assert_same_image(a.mean, b)
    with pytest.raises(StatsError, match="spp"):
        assert_same_image(a.mean, b, variance_a=a.variance)

def test_files(assert_same_image, tmp_path):
    write_exr(tmp_path / "a.exr", render(1))
    assert assert_same_image(tmp_path / "a.exr", str(tmp_path / "a.exr")).passed

def test_headers(assert_same_image):
    a, b = render(1), dataclasses.replace(render(2), camera="far")
    a.camera = "near"
    with pytest.raises(HeaderMismatch, match="differ in camera: near against far"):
        assert_same_image(a, b)
    assert assert_same_image(a, b, allow_mismatch=("camera",)).passed
    with pytest.raises(HeaderMismatch, match="max_depth: 8 against 7"):
        assert_same_image(a, dataclasses.replace(render(2), max_depth=7))
''')
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=3)
