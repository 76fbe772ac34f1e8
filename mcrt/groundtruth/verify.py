"""Listing and verifying the references of a manifest: checksums, scene hashes, agreement with the installed Mitsuba."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from mcrt.groundtruth.build import installed_versions
from mcrt.groundtruth.errors import MissingReference
from mcrt.groundtruth.manifest import read_manifest, sha256_file
from mcrt.groundtruth.spec import (MANIFEST_NAME, REFERENCE_DIR, VERIFY_BASE_SEED, VERIFY_MIN_SPP, VERIFY_PATHS,
                                 chunk_seed, data_path, display_path, rebuild_command)
from mcrt.scene import Scene, load_scene
from mcrt.util.progress import log


def entry_scene(entry: dict[str, Any]) -> Scene:
    return load_scene(data_path(entry["scene_file"]))


def entry_status(directory: Path, key: str, entry: dict[str, Any]) -> tuple[str, str]:
    """(status, detail) of one manifest entry without rendering: ok, missing, checksum, stale, no scene."""
    from mcrt.scene import SceneError

    try:
        scene = entry_scene(entry)
        cmd = rebuild_command(scene, entry["camera"], (entry["width"], entry["height"]), entry["max_depth"],
                              entry["spp"], entry.get("chunk_spp"), entry.get("base_seed", 0))
    except SceneError as e:
        return "no scene", str(e)
    path = directory / entry["file"]
    if not path.exists():
        return "missing", f"{display_path(path)} is missing; rebuild it with: {cmd}"
    digest = sha256_file(path)
    if digest != entry["sha256"]:
        return "checksum", (f"{display_path(path)}: SHA-256 {digest[:12]}... does not match the manifest's "
                            f"{entry['sha256'][:12]}...; rebuild it with: {cmd}")
    if scene.content_hash() != entry["scene_hash"]:
        return "stale", (f"built for scene hash {entry['scene_hash']}, {entry['scene_file']} now hashes to "
                         f"{scene.content_hash()}; rebuild it with: {cmd}")
    return "ok", ""


def list_references(directory: str | os.PathLike = REFERENCE_DIR) -> list[dict[str, Any]]:
    """One row per manifest entry: its fields plus ``key``, ``status`` and ``detail`` (no rendering).

    ``status`` is ``ok``, ``missing`` (no file), ``checksum`` (file differs
    from the manifest), ``stale`` (scene hash changed) or ``no scene`` (the
    scene file does not load).
    """
    directory = Path(directory)
    rows = []
    for key, entry in read_manifest(directory)["references"].items():
        status, detail = entry_status(directory, key, entry)
        rows.append({"key": key, **entry, "status": status, "detail": detail})
    return rows



@dataclass
class VerifyResult:
    """Verdict on one stored reference."""

    key: str
    status: str  # 'ok', 'failed' or 'unusable'
    checks: list[str] = field(default_factory=list)  # one line per check, in order
    comparison: Any = None  # mcrt.stats.Comparison of the fresh render against the reference
    fresh_spp: int = 0
    fresh_seed: int = 0
    wall_time: float = 0.0

    @property
    def passed(self) -> bool:
        return self.status == "ok"


def verify_references(
    keys: Sequence[str] | None = None,
    *,
    directory: str | os.PathLike = REFERENCE_DIR,
    spp: int | None = None,
    seed: int = VERIFY_BASE_SEED,
    alpha: float = 0.01,
    tile: int = 8,
    render: bool = True,
    backend: str = "llvm",
    progress: bool = True,
) -> list[VerifyResult]:
    """Check every reference (or those in ``keys``) against its checksum and the installed Mitsuba.

    For each reference: the file exists and its SHA-256 matches the manifest;
    the scene file still hashes to the reference's scene hash; and, with
    ``render``, a fresh Mitsuba render at a small budget (``spp``, default
    :data:`VERIFY_PATHS` paths per reference, at least
    :data:`VERIFY_MIN_SPP`) with a seed no build uses agrees with the stored
    mean by :func:`mcrt.stats.compare_images` (Welch tile test, each side
    with its own per-sample variance, Holm at ``alpha``). A failure there
    means the installed Mitsuba (or Dr.Jit, or mcrt's scene translation)
    renders a different image than the one that built the reference.

    Variance: the fresh render and the reference come from the same
    estimator, so if they agree they share one per-sample variance per pixel,
    and the fresh side is tested with the larger of its own estimate and the
    reference's (:func:`mcrt.stats.floor_variance`). With its own variance
    alone a small fresh render false-alarms: per-pixel variance here is
    dominated by rare caustic paths (light, mirror sphere, diffuse surface)
    that a modest render usually misses, so its mean and its variance
    estimate are both low together. ``mcrt validate --against
    reference-floor`` measures the false-alarm rate and power of the
    comparison with this floor (reports/validation/against_reference_floor/).

    The fresh render's seed is ``chunk_seed(seed, 0)``; with the default
    ``seed`` the verdict is reproducible, and a failing reference can be
    re-checked with other seeds.
    """
    from mcrt.image_files import ImageError, read_exr
    from mcrt.scene import SceneError

    directory = Path(directory)
    entries = read_manifest(directory)["references"]
    if keys:
        unknown = [k for k in keys if k not in entries]
        if unknown:
            raise MissingReference(f"no reference {', '.join(unknown)} in {display_path(directory)}/{MANIFEST_NAME} (have {', '.join(entries) or 'none'})")
        entries = {k: entries[k] for k in keys}
    results = []
    versions = None
    for key, entry in entries.items():
        t0 = time.perf_counter()
        res = VerifyResult(key, "ok")
        results.append(res)
        status, detail = entry_status(directory, key, entry)
        if status == "no scene":
            res.status = "unusable"
            res.checks.append(f"scene: {detail}")
            continue
        if status in ("missing", "checksum"):
            res.status = "failed"
            res.checks.append(f"checksum: {detail}")
            continue
        res.checks.append(f"checksum: ok (sha256 {entry['sha256'][:12]}...)")
        if status == "stale":
            res.status = "failed"
            res.checks.append(f"scene: stale: {detail}")
            continue
        res.checks.append(f"scene: ok (hash {entry['scene_hash']})")
        if not render:
            continue
        try:
            ref = read_exr(directory / entry["file"])
        except ImageError as e:
            res.status = "failed"
            res.checks.append(f"read: {e}")
            continue
        if versions is None:
            versions = installed_versions(backend)
        drift = [f"{k.split('_')[0]} {entry[k]} -> {versions[k]}" for k in ("mitsuba_version", "drjit_version") if entry.get(k) != versions[k]]
        res.checks.append("versions: " + (f"built with Mitsuba {entry['mitsuba_version']}, Dr.Jit {entry['drjit_version']}, {entry['variant']}; "
                                          + ("installed: same" if not drift else "installed differs: " + ", ".join(drift))))
        w, h = entry["width"], entry["height"]
        n = int(spp) if spp else max(VERIFY_MIN_SPP, VERIFY_PATHS // (w * h))
        fresh_seed = chunk_seed(seed, 0)
        if fresh_seed in entry.get("chunk_seeds", []):
            fresh_seed = chunk_seed(seed, 1)
        res.fresh_spp, res.fresh_seed = n, fresh_seed
        from mcrt.render import render as render_image
        from mcrt.stats import compare

        log(f"verify {key}: rendering {w}x{h} at {n} spp (seed {fresh_seed})", progress)
        try:
            scene = entry_scene(entry)
            s = scene.settings(camera=entry["camera"], width=w, height=h, spp=n, max_depth=entry["max_depth"],
                               rr_depth=entry.get("rr_depth"))
            fresh = render_image(scene, s, renderer="mitsuba", seed=fresh_seed, backend=backend, progress=progress)
        except (SceneError, RuntimeError, ValueError) as e:
            res.status = "unusable"
            res.checks.append(f"render: {e}")
            continue
        # Both sides are the same estimator, so under "same image" they share one per-sample
        # variance per pixel; the fresh side takes the larger of the two estimates (see docstring).
        cmp = compare(fresh, ref, policy="reference-floor", alpha=alpha, tile=tile)
        res.comparison = cmp
        res.checks.append(f"agreement: {n} fresh spp vs {entry['spp']} reference spp: {cmp.summary()}")
        if not cmp.passed:
            res.status = "failed"
        res.wall_time = time.perf_counter() - t0
    return results
