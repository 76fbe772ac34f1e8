"""Ground truth: Mitsuba references that are reproducible, resumable and verifiable.

``reference/`` holds the Mitsuba 3 renders that tests, reports and grading
compare against, one OpenEXR file per (scene, camera, resolution, max depth)
with the mean and the per-sample variance, and ``reference/manifest.json``
listing every reference with its SHA-256 checksum and provenance (Mitsuba
and Dr.Jit versions, variant, scene hash, spp, chunk seeds, max depth, render
time, machine, date and the command that rebuilds it).

Chunks
------
A reference of ``spp`` samples per pixel is rendered as ``ceil(spp /
chunk_spp)`` independent chunks. Chunk ``i`` is one Mitsuba render
(:func:`mcrt.render.render`, renderer ``mitsuba``) with its own seed
:func:`chunk_seed` ``(base_seed, i)`` (a hash of both, so builds with other
base seeds draw other streams) and ``min(chunk_spp, spp - i chunk_spp)``
samples per pixel. Each finished chunk is written atomically to
``reference/chunks/<key>/chunk_0007.exr`` (not committed), so an interrupted
build (Ctrl-C, a killed process, a full disk) continues where it stopped: a
chunk file that reads back with the expected seed, spp, scene hash, camera,
size, max depth, Mitsuba version and variant is reused, anything else is
rendered again. Chunks merge exactly with :func:`mcrt.film.merge`
(sample-weighted sums of x and x^2 in float64), always in chunk order, so the
reference does not depend on which worker finished first.

Chunks run in a local process pool (:data:`DEFAULT_WORKERS` workers), or on a
Dask cluster when ``scheduler`` is a ``dask.distributed`` scheduler address
(``tcp://host:8786``): workers only render and send the images back; only
the machine that runs the build writes files.

Every file is written to a temporary file in the target folder and then moved
over the target (``os.replace``), so a failed write never leaves a
half-written file where a good reference stood.

Reading references
------------------
:func:`load_reference` is what tests use. It never renders: a missing
reference, one whose checksum does not match the manifest, or one built for
another version of the scene (scene hash changed) raises a
:class:`ReferenceUnavailable` whose message names the command that rebuilds
it.

Modules: :mod:`.spec` (names, seeds, rebuild commands, the standard set),
:mod:`.errors`, :mod:`.manifest` (checksums, atomic writes, the lock),
:mod:`.build`, :mod:`.load`, :mod:`.verify` (list and verify),
:mod:`.text` (the ``list`` table and ``verify`` report), :mod:`.cli`
(``mcrt reference``).
"""

from __future__ import annotations

from mcrt.groundtruth.build import BuildResult, build_reference
from mcrt.groundtruth.cli import register
from mcrt.groundtruth.errors import CorruptReference, MissingReference, ReferenceUnavailable, StaleReference
from mcrt.groundtruth.load import load_reference
from mcrt.groundtruth.manifest import read_manifest, sha256_file
from mcrt.groundtruth.spec import (CHUNK_DIR_NAME, DEFAULT_WORKERS, MANIFEST_NAME, REFERENCE_DIR, SCHEMA, STANDARD,
                                 VERIFY_BASE_SEED, ReferenceSpec, chunk_seed, rebuild_command, reference_key)
from mcrt.groundtruth.text import format_table, format_verify
from mcrt.groundtruth.verify import VerifyResult, list_references, verify_references

__all__ = [
    "REFERENCE_DIR",
    "MANIFEST_NAME",
    "CHUNK_DIR_NAME",
    "DEFAULT_WORKERS",
    "VERIFY_BASE_SEED",
    "SCHEMA",
    "STANDARD",
    "ReferenceUnavailable",
    "MissingReference",
    "StaleReference",
    "CorruptReference",
    "ReferenceSpec",
    "BuildResult",
    "VerifyResult",
    "reference_key",
    "chunk_seed",
    "rebuild_command",
    "build_reference",
    "load_reference",
    "list_references",
    "verify_references",
    "read_manifest",
    "sha256_file",
    "format_table",
    "format_verify",
    "register",
]
