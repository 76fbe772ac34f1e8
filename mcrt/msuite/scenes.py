"""The scenes of a Mitsuba-style render-test folder, and the part held out of tuning.

Layout (Mitsuba 3's ``tests/scenes``): ``<group>/<test>_<integrator>.xml``
with ``<group>/refs/<test>_ref_rgb.exr`` and ``<test>_ref_rgb_var.exr``.
Scenes without both reference files are listed as skipped.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

#: Scenes kept out of tuning: chosen before any was rendered (one per kind: instancing, a texture lookup with a
#: gaussian filter, mesh attributes, a rough dielectric, an environment map), looked at last.
HELD_OUT = (
    "instancing/test_instancing_path",
    "texture_interp/test_texture_interp_direct",
    "mesh_attributes/test_mesh_attributes_3_vertex_direct",
    "bsdf_spheres/test_roughdielectric_path",
    "bsdf_spheres/test_envmap_path",
)


@dataclass(frozen=True)
class Case:
    """One scene of the suite: ``name`` is ``<group>/<file stem>``."""

    name: str
    xml: Path
    ref: Path
    ref_var: Path

    @property
    def held_out(self) -> bool:
        return self.name in HELD_OUT


def scene_root(folder: Path) -> Path:
    """``folder/tests/scenes`` when it exists (the repository's root given), else ``folder`` itself."""
    folder = Path(folder)
    return folder / "tests" / "scenes" if (folder / "tests" / "scenes").is_dir() else folder


def find_cases(folder: Path) -> tuple[list[Case], list[tuple[str, str]]]:
    """The scenes with their reference pair, sorted by name, and ``(name, why)`` for those skipped."""
    root = scene_root(folder)
    if not root.is_dir():
        raise ValueError(f"{folder}: no such folder")
    cases, skipped = [], []
    for xml in sorted(root.glob("*/*.xml")):
        name = f"{xml.parent.name}/{xml.stem}"
        test = xml.stem.rsplit("_", 1)[0]
        ref = xml.parent / "refs" / f"{test}_ref_rgb.exr"
        var = xml.parent / "refs" / f"{test}_ref_rgb_var.exr"
        if ref.is_file() and var.is_file():
            cases.append(Case(name, xml, ref, var))
        else:
            skipped.append((name, f"no {ref.name} and {var.name} beside it"))
    if not cases:
        raise ValueError(f"{folder}: no scene with a reference pair under {root} (expected <group>/<test>_<integrator>.xml "
                         "and <group>/refs/<test>_ref_rgb.exr, _var.exr)")
    return cases, skipped
