"""Ground-truth references: chunk merging, resumable and atomic builds, Dask, manifest, load errors.

Builds here are tiny (8 x 8 pixels, a few dozen spp) in a temporary folder,
so the file runs in well under a minute on two CPU cores. The last tests check
the committed references in reference/ without rendering anything.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mcrt
from mcrt import groundtruth as ref
from mcrt.exitcodes import EXIT_FAILED, EXIT_OK, EXIT_UNUSABLE
from mcrt.groundtruth import build as ref_build
from mcrt.groundtruth import manifest as ref_manifest
from mcrt.film import RenderResult, merge
from mcrt.image_files import ImageError, read_exr, write_exr

RES = 8
SPP, CHUNK = 48, 16  # three chunks


@pytest.fixture(scope="module")
def scene():
    return mcrt.load_scene(mcrt.CANONICAL)


@pytest.fixture(scope="module")
def built(scene, tmp_path_factory):
    """A three-chunk 8x8 reference, built once; tests copy the folder before changing it."""
    d = tmp_path_factory.mktemp("ref")
    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    return d, b


def _copy(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst)
    return dst


def _same_image(a: RenderResult, b: RenderResult) -> None:
    np.testing.assert_array_equal(a.mean, b.mean)
    np.testing.assert_array_equal(a.variance, b.variance)
    assert a.spp == b.spp


# --------------------------------------------------------------------------
# Seeds and names
# --------------------------------------------------------------------------


def test_chunk_seeds_are_deterministic_and_distinct():
    seeds = [ref.chunk_seed(0, i) for i in range(1000)]
    assert seeds == [ref.chunk_seed(0, i) for i in range(1000)]
    assert len(set(seeds)) == 1000 and all(0 <= s < 2**31 for s in seeds)
    assert not set(seeds) & {ref.chunk_seed(1, i) for i in range(1000)}
    assert ref.chunk_seed(ref.VERIFY_BASE_SEED, 0) not in seeds


def test_reference_key():
    assert ref.reference_key("canonical", "near", 64, 8) == "canonical_near_64x64_d8"
    assert ref.reference_key("canonical", "far", (32, 16), -1) == "canonical_far_32x16_dinf"


# --------------------------------------------------------------------------
# Merging chunks
# --------------------------------------------------------------------------


def _chunk_from_samples(x: np.ndarray, seed: int) -> RenderResult:
    """A RenderResult from per-sample values x (n, H, W, 3), as a renderer would store it."""
    x = x.astype(np.float64)
    return RenderResult(mean=x.mean(0).astype(np.float32), variance=x.var(0, ddof=1).astype(np.float32),
                        spp=x.shape[0], seed=seed, max_depth=8, renderer="test")


def test_merge_is_exact_in_any_order():
    # Heavy-tailed samples (lognormal with rare huge values), as a path tracer makes them.
    # Seed pinned so the test sees the same samples on every run.
    rng = np.random.default_rng(20240611)
    x = rng.lognormal(0.0, 1.5, size=(200, 4, 5, 3))
    x[rng.random(x.shape) < 0.01] *= 100.0
    sizes = [7, 64, 2, 100, 27]
    parts = np.split(x, np.cumsum(sizes)[:-1])
    chunks = [_chunk_from_samples(p, i) for i, p in enumerate(parts)]
    whole = _chunk_from_samples(x, 0)

    merged = merge(chunks)
    assert merged.spp == 200
    for perm in ([4, 3, 2, 1, 0], [2, 0, 4, 1, 3], [1, 4, 0, 3, 2]):
        other = merge([chunks[i] for i in perm])
        np.testing.assert_allclose(other.mean, merged.mean, rtol=1e-6)
        np.testing.assert_allclose(other.variance, merged.variance, rtol=1e-6)
    # Merging equals the moments of all samples at once (up to the float32 the chunks are stored in).
    np.testing.assert_allclose(merged.mean, whole.mean, rtol=1e-6)
    np.testing.assert_allclose(merged.variance, whole.variance, rtol=1e-5)


def test_reference_is_its_chunks_merged(built):
    d, b = built
    folder = d / ref.CHUNK_DIR_NAME / b.key
    chunks = [read_exr(folder / f"chunk_{i:04d}.exr") for i in range(3)]
    assert [c.seed for c in chunks] == [ref.chunk_seed(0, i) for i in range(3)] == b.entry["chunk_seeds"]
    assert [c.spp for c in chunks] == [CHUNK] * 3
    stored = read_exr(b.path)
    _same_image(stored, merge(chunks))
    shuffled = merge([chunks[2], chunks[0], chunks[1]])
    np.testing.assert_allclose(shuffled.mean, stored.mean, rtol=1e-6)
    np.testing.assert_allclose(shuffled.variance, stored.variance, rtol=1e-6)
    assert stored.spp == SPP and stored.scene_hash == b.entry["scene_hash"]


def test_chunk_sizes_cover_spp(scene, tmp_path):
    b = ref.build_reference(scene, "far", RES, 2, 40, chunk_spp=16, directory=tmp_path, progress=False)
    assert b.result.spp == 40 and b.rendered == [0, 1, 2]
    assert read_exr(tmp_path / "chunks" / b.key / "chunk_0002.exr").spp == 8
    with pytest.raises(ValueError, match="last chunk"):
        ref.build_reference(scene, "far", RES, 2, 33, chunk_spp=16, directory=tmp_path, progress=False)


# --------------------------------------------------------------------------
# Resuming
# --------------------------------------------------------------------------


def test_resume_renders_only_missing_or_corrupt_chunks(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    first = read_exr(built[1].path)
    folder = d / "chunks" / built[1].key

    (folder / "chunk_0001.exr").unlink()
    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert b.rendered == [1] and b.reused == [0, 2]
    _same_image(read_exr(b.path), first)

    data = (folder / "chunk_0002.exr").read_bytes()
    (folder / "chunk_0002.exr").write_bytes(data[: len(data) // 2])  # truncated, as by a full disk
    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert b.rendered == [2] and b.reused == [0, 1]
    _same_image(read_exr(b.path), first)

    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert b.rendered == [] and b.reused == [0, 1, 2]
    _same_image(read_exr(b.path), first)


def test_interrupted_build_continues_where_it_stopped(scene, built, tmp_path, monkeypatch):
    real = ref_build._render_chunk
    calls = []

    def interrupted(task):
        calls.append(task.index)
        if task.index == 2:
            raise KeyboardInterrupt  # Ctrl-C during the third chunk
        return real(task)

    monkeypatch.setattr(ref_build, "_render_chunk", interrupted)
    with pytest.raises(KeyboardInterrupt):
        ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=tmp_path, workers=1, progress=False)
    assert calls == [0, 1, 2]
    assert not (tmp_path / f"{built[1].key}.exr").exists() and not (tmp_path / "manifest.json").exists()
    monkeypatch.setattr(ref_build, "_render_chunk", real)
    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=tmp_path, progress=False)
    assert b.rendered == [2] and b.reused == [0, 1]
    _same_image(b.result, read_exr(built[1].path))


def test_more_spp_reuses_existing_chunks(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    b = ref.build_reference(scene, "near", RES, 8, SPP + CHUNK, chunk_spp=CHUNK, directory=d, progress=False)
    assert b.rendered == [3] and b.reused == [0, 1, 2] and b.result.spp == SPP + CHUNK


def test_stale_chunks_are_rendered_again(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    other = replace(scene, light=replace(scene.light, radiance=(21.0, 21.0, 21.0)))
    b = ref.build_reference(other, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert b.rendered == [0, 1, 2] and b.entry["scene_hash"] == other.content_hash() != scene.content_hash()


# --------------------------------------------------------------------------
# Atomic writes
# --------------------------------------------------------------------------


def test_failed_write_leaves_previous_reference_untouched(scene, built, tmp_path, monkeypatch):
    import mcrt.image_files as imageio

    d = _copy(built[0], tmp_path / "ref")
    path = d / built[1].path.name
    before, manifest_before = path.read_bytes(), (d / "manifest.json").read_bytes()

    def disk_full(tmp, header, channels):
        with open(tmp, "wb") as f:
            f.write(b"\x76\x2f\x31\x01 half an EXR")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(imageio, "_write_exr_file", disk_full)
    with pytest.raises(ImageError, match="No space left"):
        ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert path.read_bytes() == before
    assert (d / "manifest.json").read_bytes() == manifest_before
    assert not [p for p in d.rglob("*") if p.name.endswith(".tmp")]
    monkeypatch.undo()
    ref.load_reference(scene, "near", RES, 8, directory=d)  # still valid


def test_failed_manifest_write_keeps_old_manifest(scene, built, tmp_path, monkeypatch):
    d = _copy(built[0], tmp_path / "ref")
    manifest_before = (d / "manifest.json").read_bytes()

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ref_manifest.os, "replace", fail)
    with pytest.raises(OSError):
        ref_manifest.write_manifest(d, {"references": {}})
    monkeypatch.undo()
    assert (d / "manifest.json").read_bytes() == manifest_before
    assert not list(d.glob(".*.tmp"))


def test_stale_temporary_files_are_cleaned(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    folder = d / "chunks" / built[1].key
    dead = folder / ".chunk_0001.exr.999999999.abcd1234.tmp"  # no such pid
    dead.write_bytes(b"partial")
    ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=d, progress=False)
    assert not dead.exists()


# --------------------------------------------------------------------------
# Parallel builds: local processes and Dask
# --------------------------------------------------------------------------


def test_process_pool_gives_the_serial_result(scene, built, tmp_path):
    b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=tmp_path, workers=2, threads=1, progress=False)
    assert sorted(b.rendered) == [0, 1, 2]
    _same_image(b.result, read_exr(built[1].path))


def test_dask_local_cluster_gives_the_local_result(scene, built, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None) as cluster:
        b = ref.build_reference(scene, "near", RES, 8, SPP, chunk_spp=CHUNK, directory=tmp_path,
                                scheduler=cluster.scheduler_address, progress=False)
    assert b.rendered == [0, 1, 2]
    local = read_exr(built[1].path)
    # Same chunks, merged in chunk order: equal up to float merge order (here exactly).
    np.testing.assert_allclose(b.result.mean, local.mean, rtol=1e-6, atol=0)
    np.testing.assert_allclose(b.result.variance, local.variance, rtol=1e-5, atol=0)
    assert b.entry["chunk_seeds"] == built[1].entry["chunk_seeds"]


# --------------------------------------------------------------------------
# Loading: missing, stale, tampered
# --------------------------------------------------------------------------


def test_missing_reference_names_the_rebuild_command(scene, tmp_path):
    with pytest.raises(ref.MissingReference) as e:
        ref.load_reference(scene, "far", 64, 2, directory=tmp_path)
    msg = str(e.value)
    assert "canonical_far_64x64_d2" in msg
    assert "mcrt reference build --camera far --res 64 --max-depth 2 --spp" in msg
    assert e.value.command in msg


def test_missing_file_names_the_rebuild_command(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    (d / built[1].path.name).unlink()
    with pytest.raises(ref.MissingReference, match=f"mcrt reference build --camera near --res {RES} --max-depth 8 --spp {SPP}"):
        ref.load_reference(scene, "near", RES, 8, directory=d)


def test_stale_reference_names_the_rebuild_command(scene, built):
    changed = replace(scene, light=replace(scene.light, radiance=(21.0, 21.0, 21.0)))
    with pytest.raises(ref.StaleReference) as e:
        ref.load_reference(changed, "near", RES, 8, directory=built[0])
    assert "stale" in str(e.value) and changed.content_hash() in str(e.value)
    assert f"mcrt reference build --camera near --res {RES} --max-depth 8 --spp {SPP} --chunk-spp {CHUNK}" in str(e.value)


def test_manifest_checksums_and_tampering(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    entry = ref.read_manifest(d)["references"][built[1].key]
    path = d / entry["file"]
    assert entry["sha256"] == ref.sha256_file(path) and entry["bytes"] == path.stat().st_size
    for k in ("scene_hash", "camera", "width", "max_depth", "spp", "chunk_seeds", "mitsuba_version", "drjit_version",
              "variant", "render_time_s", "machine", "date", "command"):
        assert k in entry
    assert [r["status"] for r in ref.list_references(d)] == ["ok"]
    assert all(r.passed for r in ref.verify_references(directory=d, render=False, progress=False))

    data = bytearray(path.read_bytes())
    data[-10] ^= 0xFF  # one flipped bit-pattern in the pixel data
    path.write_bytes(bytes(data))
    rows = ref.list_references(d)
    assert rows[0]["status"] == "checksum" and "mcrt reference build" in rows[0]["detail"]
    (res,) = ref.verify_references(directory=d, render=False, progress=False)
    assert res.status == "failed" and "does not match" in " ".join(res.checks)
    with pytest.raises(ref.CorruptReference, match="mcrt reference build"):
        ref.load_reference(scene, "near", RES, 8, directory=d)


# --------------------------------------------------------------------------
# Verify with fresh renders
# --------------------------------------------------------------------------


def test_verify_renders_and_catches_a_different_image(scene, built, tmp_path):
    d = _copy(built[0], tmp_path / "ref")
    (ok,) = ref.verify_references(directory=d, spp=256, progress=False)
    assert ok.passed and ok.comparison is not None and ok.comparison.passed
    assert ok.fresh_seed not in built[1].entry["chunk_seeds"]

    # A reference that another Mitsuba would not reproduce: 20 % brighter, checksum made consistent.
    r = read_exr(d / built[1].path.name)
    write_exr(d / built[1].path.name, replace(r, mean=r.mean * 1.2))
    manifest = json.loads((d / "manifest.json").read_text())
    manifest["references"][built[1].key]["sha256"] = ref.sha256_file(d / built[1].path.name)
    (d / "manifest.json").write_text(json.dumps(manifest))
    (bad,) = ref.verify_references(directory=d, spp=256, progress=False)
    assert bad.status == "failed" and not bad.comparison.passed
    report = ref.format_verify([bad])
    assert "FAILED" in report and "DIFFERENT" in report and "0 of 1 references verified" in report


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------


def _cli(*argv) -> int:
    ap = argparse.ArgumentParser(prog="mcrt")
    ref.register(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(list(argv))
    return args.func(args)


def test_cli_build_list_verify(tmp_path, capsys):
    d = str(tmp_path)
    assert _cli("reference", "build", "--camera", "near", "far", "--res", str(RES), "--max-depth", "2",
                "--spp", "32", "--chunk-spp", "16", "--dir", d, "--quiet") == EXIT_OK
    assert sorted(ref.read_manifest(d)["references"]) == ["canonical_far_8x8_d2", "canonical_near_8x8_d2"]
    capsys.readouterr()
    assert _cli("reference", "list", "--dir", d) == EXIT_OK
    out = capsys.readouterr().out
    assert "canonical_far_8x8_d2" in out and "status" in out and "2 references" in out
    assert _cli("reference", "verify", "--dir", d, "--checksums-only") == EXIT_OK
    assert _cli("reference", "verify", "canonical_near_8x8_d2", "--dir", d, "--spp", "64", "--quiet") == EXIT_OK
    out = capsys.readouterr().out
    assert "OK" in out and "agreement" in out and "1 of 1 references verified" in out

    p = tmp_path / "canonical_far_8x8_d2.exr"
    p.write_bytes(p.read_bytes()[:-1] + b"\0")
    assert _cli("reference", "verify", "--dir", d, "--checksums-only") == EXIT_FAILED
    assert _cli("reference", "list", "--dir", d) == EXIT_FAILED


def test_cli_unusable_input(tmp_path, capsys):
    assert _cli("reference", "verify", "--dir", str(tmp_path)) == EXIT_UNUSABLE
    assert _cli("reference", "verify", "nosuch", "--dir", str(tmp_path)) == EXIT_UNUSABLE
    assert _cli("reference", "build", "--camera", "nosuch", "--dir", str(tmp_path)) == EXIT_UNUSABLE
    assert "nosuch" in capsys.readouterr().err
    for sub in ("build", "verify", "list"):
        with pytest.raises(SystemExit) as e:
            _cli("reference", sub, "--help")
        assert e.value.code == 0
    assert "--scheduler" in capsys.readouterr().out


# --------------------------------------------------------------------------
# The committed references (no rendering)
# --------------------------------------------------------------------------


def test_committed_references_are_listed_and_valid(scene):
    if not (ref.REFERENCE_DIR / ref.MANIFEST_NAME).exists():
        pytest.fail(f"reference/{ref.MANIFEST_NAME} is missing; build the references with: mcrt reference build --standard")
    entries = ref.read_manifest()["references"]
    for spec in ref.STANDARD:
        key = ref.reference_key(scene.name, spec.camera, spec.res, spec.max_depth)
        assert key in entries, f"{key} is not committed; build it with: {ref.rebuild_command(scene, spec.camera, spec.res, spec.max_depth, spec.spp)}"
        r = ref.load_reference(scene, spec.camera, spec.res, spec.max_depth)
        assert r.spp >= spec.spp and r.renderer == "mitsuba" and r.variance is not None
        assert np.isfinite(r.mean).all() and (r.mean >= 0).all()
    rows = ref.list_references()
    assert all(row["status"] == "ok" for row in rows), [(row["key"], row["detail"]) for row in rows if row["status"] != "ok"]
    assert not (ref.REFERENCE_DIR / ref.CHUNK_DIR_NAME).exists() or _ignored("reference/chunks/x.exr")


def _ignored(path: str) -> bool:
    import subprocess

    root = ref.REFERENCE_DIR.parent  # the checkout
    r = subprocess.run(["git", "check-ignore", "-q", path], cwd=root, capture_output=True)
    return r.returncode == 0
