"""Names, seeds and commands of references: what a reference is called, which seeds build it, how to rebuild it."""

from __future__ import annotations

import hashlib
import math
import os
import shlex
from dataclasses import dataclass
from pathlib import Path

from mcrt.scene import CANONICAL, DATA_DIR, Scene, load_scene

#: Where committed references and the manifest live: reference/ of a checkout, mcrt.data when installed.
REFERENCE_DIR = DATA_DIR
#: What the manifest calls that folder: its paths read ``reference/scenes/canonical.toml`` in either.
DATA_NAME = "reference"
MANIFEST_NAME = "manifest.json"
#: Sub-folder of the reference folder holding per-chunk files (git-ignored).
CHUNK_DIR_NAME = "chunks"
#: Schema tag of manifest.json.
SCHEMA = "mcrt.reference.manifest/1"

#: Paths traced per chunk when ``chunk_spp`` is not given: 4096 spp at 64x64, 1024 at 128x128.
CHUNK_PATHS = 1 << 24
#: Samples per pixel of a build when ``spp`` is not given.
DEFAULT_SPP = 16384
#: Base seed of builds; chunk seeds are hashes of (base seed, chunk index).
DEFAULT_BASE_SEED = 0
#: Base seed of the fresh renders of :func:`mcrt.groundtruth.verify_references` (never used
#: by a build with the default base seed).
VERIFY_BASE_SEED = 1_000_003
#: Paths per reference that :func:`mcrt.groundtruth.verify_references` renders by default
#: (at least :data:`VERIFY_MIN_SPP` samples per pixel).
VERIFY_PATHS = 1 << 22
VERIFY_MIN_SPP = 256
#: Local worker processes of a build. Dr.Jit's LLVM backend already spreads each
#: kernel over every core with its own thread pool, so by default one worker
#: renders in this process; more workers split the cores between processes.
DEFAULT_WORKERS = 1


@dataclass(frozen=True)
class ReferenceSpec:
    """One committed reference: what ``mcrt reference build --standard`` builds."""

    camera: str
    res: int
    max_depth: int
    spp: int


#: The committed references of the canonical scene (see README, "Ground truth").
STANDARD: tuple[ReferenceSpec, ...] = (
    *(ReferenceSpec(cam, 64, 8, 32768) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, 2, 65536) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, 1, 65536) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 64, -1, 16384) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 128, 8, 8192) for cam in ("near", "far")),
    *(ReferenceSpec(cam, 128, 2, 16384) for cam in ("near", "far")),
    # The report-resolution reference.
    ReferenceSpec("near", 256, 8, 16384),
)


def size_of(res: int | tuple[int, int]) -> tuple[int, int]:
    """(width, height) from N or (W, H)."""
    if isinstance(res, (tuple, list)):
        w, h = (int(x) for x in res)
    else:
        w = h = int(res)
    if w < 1 or h < 1:
        raise ValueError(f"resolution must be positive, got {w}x{h}")
    return w, h


def depth_label(max_depth: int) -> str:
    return "inf" if max_depth == -1 else str(int(max_depth))


def reference_key(scene_name: str, camera: str, res: int | tuple[int, int], max_depth: int) -> str:
    """File stem of a reference: ``<scene>_<camera>_<W>x<H>_d<D>`` (``dinf`` for max depth -1)."""
    w, h = size_of(res)
    return f"{scene_name}_{camera}_{w}x{h}_d{depth_label(max_depth)}"


def chunk_seed(base_seed: int, index: int) -> int:
    """Seed of chunk ``index`` of a build with ``base_seed``: a 31-bit hash of both."""
    key = f"mcrt.reference/{int(base_seed)}/{int(index)}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=4).digest(), "little") & 0x7FFFFFFF


def chunk_spp_for(res: int | tuple[int, int], spp: int) -> int:
    """Default samples per pixel of one chunk: about :data:`CHUNK_PATHS` paths, a power of two."""
    w, h = size_of(res)
    n = max(1, CHUNK_PATHS // (w * h))
    n = 1 << (n.bit_length() - 1)
    return max(1, min(n, int(spp)))


def chunk_sizes(spp: int, chunk_spp: int) -> list[int]:
    n = math.ceil(spp / chunk_spp)
    return [min(chunk_spp, spp - i * chunk_spp) for i in range(n)]


def _scene_arg(scene: Scene) -> str:
    """``--scene PATH`` for a scene that is not the canonical file, else ''."""
    try:
        if Path(scene.path).resolve() == CANONICAL.resolve():
            return ""
    except (OSError, ValueError):
        pass
    return f"--scene {shlex.quote(display_path(scene.path))} "


def rebuild_command(
    scene: Scene,
    camera: str,
    res: int | tuple[int, int],
    max_depth: int,
    spp: int | None = None,
    chunk_spp: int | None = None,
    base_seed: int = DEFAULT_BASE_SEED,
) -> str:
    """The ``mcrt reference build`` command line that (re)builds one reference."""
    w, h = size_of(res)
    size = f"--res {w}" if w == h else f"--width {w} --height {h}"
    spp = int(spp) if spp else standard_spp(camera, (w, h), max_depth)
    cmd = f"mcrt reference build {_scene_arg(scene)}--camera {camera} {size} --max-depth {max_depth} --spp {spp}"
    if chunk_spp and chunk_spp != chunk_spp_for((w, h), spp):
        cmd += f" --chunk-spp {chunk_spp}"
    if base_seed != DEFAULT_BASE_SEED:
        cmd += f" --seed {base_seed}"
    return cmd


def standard_spp(camera: str, size: tuple[int, int], max_depth: int) -> int:
    for s in STANDARD:
        if (s.camera, (s.res, s.res), s.max_depth) == (camera, size, max_depth):
            return s.spp
    return DEFAULT_SPP


def display_path(path: str | os.PathLike) -> str:
    """A path inside the ground truth's folder as ``reference/...``, whether that folder is a checkout's or installed; others as given."""
    p = Path(path)
    try:
        return (Path(DATA_NAME) / p.resolve().relative_to(REFERENCE_DIR)).as_posix()
    except (ValueError, OSError):
        return str(p)


def data_path(recorded: str | os.PathLike) -> Path:
    """The file a manifest's ``reference/...`` path names (the inverse of :func:`display_path`); other paths as given."""
    p = Path(recorded)
    if not p.is_absolute() and p.parts[:1] == (DATA_NAME,):
        return REFERENCE_DIR.joinpath(*p.parts[1:])
    return p


def resolve_scene(scene: Scene | str | os.PathLike | None) -> Scene:
    if scene is None:
        return load_scene(CANONICAL)
    if isinstance(scene, Scene):
        return scene
    return load_scene(scene)
