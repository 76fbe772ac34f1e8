"""Reading a committed reference: never renders; a reference that cannot be used raises, naming the rebuild command."""

from __future__ import annotations

import os
from pathlib import Path

from mcrt.film import RenderResult
from mcrt.groundtruth.errors import CorruptReference, MissingReference, StaleReference
from mcrt.groundtruth.manifest import read_manifest, sha256_file
from mcrt.groundtruth.spec import MANIFEST_NAME, REFERENCE_DIR, display_path, rebuild_command, reference_key, resolve_scene, size_of
from mcrt.scene import Scene


def load_reference(
    scene: Scene | str | os.PathLike | None,
    camera: str,
    res: int | tuple[int, int],
    max_depth: int,
    *,
    directory: str | os.PathLike = REFERENCE_DIR,
    check_checksum: bool = True,
) -> RenderResult:
    """The committed reference for (scene, camera, res, max depth); never renders.

    Raises
    ------
    MissingReference
        No manifest entry or no file.
    CorruptReference
        The file's SHA-256 differs from the manifest's, or it does not read.
    StaleReference
        The reference was rendered for another version of the scene (its
        scene hash is not ``scene.content_hash()``).

    Every message names the ``mcrt reference build`` command that rebuilds
    the reference.
    """
    from mcrt.image_files import ImageError, read_exr

    scene = resolve_scene(scene)
    w, h = size_of(res)
    directory = Path(directory)
    key = reference_key(scene.name, camera, (w, h), max_depth)
    data = read_manifest(directory)
    entry = data["references"].get(key)
    cmd = rebuild_command(scene, camera, (w, h), max_depth, *((entry["spp"], entry.get("chunk_spp"), entry.get("base_seed", 0)) if entry else ()))
    where = display_path(directory)
    if entry is None:
        raise MissingReference(f"no reference {key} in {where}/{MANIFEST_NAME}; build it with: {cmd}", cmd)
    path = directory / entry["file"]
    if not path.exists():
        raise MissingReference(f"reference file {display_path(path)} is missing; rebuild it with: {cmd} "
                               f"(or restore it with `git checkout -- {display_path(path)}`)", cmd)
    if check_checksum:
        digest = sha256_file(path)
        if digest != entry["sha256"]:
            raise CorruptReference(f"{display_path(path)}: SHA-256 {digest[:12]}... does not match the manifest's "
                                   f"{entry['sha256'][:12]}... (modified or corrupt); rebuild it with: {cmd}", cmd)
    want = scene.content_hash()
    if entry["scene_hash"] != want:
        raise StaleReference(f"reference {key} is stale: built for scene hash {entry['scene_hash']}, the scene "
                             f"{display_path(scene.path)} now hashes to {want}; rebuild it with: {cmd}", cmd)
    try:
        r = read_exr(path)
    except ImageError as e:
        raise CorruptReference(f"{e}; rebuild it with: {cmd}", cmd) from None
    if r.scene_hash != want or r.shape != (h, w) or r.max_depth != max_depth or r.camera != camera:
        raise StaleReference(f"{display_path(path)} does not hold {key} for scene hash {want} "
                             f"(it has {r.camera} {r.shape[1]}x{r.shape[0]} d{r.max_depth}, scene hash {r.scene_hash}); "
                             f"rebuild it with: {cmd}", cmd)
    return r
