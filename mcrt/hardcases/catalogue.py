"""The catalogue of hard cases: variants of the canonical room, each stressing one numerical weakness."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from mcrt.scene import CANONICAL, SCENE_DIR, Scene, load_scene

#: Scene files of the hard cases.
HARD_DIR = SCENE_DIR / "hard"



@dataclass(frozen=True)
class HardCase:
    """One hard case: where its scene comes from, which camera sees it, what it stresses.

    ``source`` is a file name under reference/scenes/hard/ or ``canonical.toml``;
    ``factor`` and ``offset`` transform the loaded scene with
    :meth:`Scene.scaled`. ``expect`` is ``'agree'`` (both renderers finite,
    non-negative and consistent) or ``'refused'`` (beyond float32's limits:
    :func:`mcrt.precision.check_precision` must refuse it). ``known_issue``,
    when set, explains why the case fails today and what would fix it.
    """

    name: str
    sentence: str
    source: str
    camera: str
    factor: float = 1.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    intersector: str = "convex"
    expect: str = "agree"
    known_issue: str = ""

    @property
    def transformed(self) -> bool:
        return self.factor != 1.0 or any(self.offset)

    def source_path(self) -> Path:
        return CANONICAL if self.source == "canonical.toml" else HARD_DIR / self.source

    def reference_scene(self) -> Scene:
        """The untransformed scene: the reference of the error columns (same expected image)."""
        return load_scene(self.source_path())

    def scene(self) -> Scene:
        base = self.reference_scene()
        if not self.transformed:
            return base
        return replace(base.scaled(self.factor, self.offset), name=self.name, description=self.sentence)


def _file_case(name: str, camera: str, **kw) -> HardCase:
    """A case whose sentence is its scene file's ``description``."""
    return HardCase(name, load_scene(HARD_DIR / f"{name}.toml").description, f"{name}.toml", camera, **kw)



CATALOGUE: tuple[HardCase, ...] = (
    _file_case("light_on_ceiling", "near"),
    _file_case("light_on_wall", "wall"),
    _file_case("light_low", "under"),
    _file_case("sphere_tangent", "near"),
    _file_case("sphere_tiny", "zoom"),
    _file_case("tetra_on_floor", "edge_on"),
    _file_case("grazing_wall", "graze"),
    _file_case("eye_corner", "corner"),
    HardCase("scaled_1e-3", "The whole scene, cameras included, scaled by 1e-3 about the origin: the expected image is unchanged.",
             "canonical.toml", "near", factor=1e-3),
    HardCase("scaled_1e3", "The whole scene, cameras included, scaled by 1e3 about the origin: the expected image is unchanged.",
             "canonical.toml", "near", factor=1e3),
    HardCase("moved_1e3", "The scene moved by (1e3, 1e3, 1e3), within float32's limit: the expected image is unchanged.",
             "canonical.toml", "near", offset=(1e3, 1e3, 1e3)),
    HardCase("moved_1e4", "The scene moved by (1e4, 1e4, 1e4), beyond float32's limit (spawn offsets of 0.08): mcrt must refuse it.",
             "canonical.toml", "near", offset=(1e4, 1e4, 1e4), expect="refused"),
    _file_case("tiny_light", "far"),
    _file_case("shared_edges", "fan", intersector="triangles"),
)


def case(name: str) -> HardCase:
    for c in CATALOGUE:
        if c.name == name:
            return c
    raise ValueError(f"unknown hard case {name!r} (have {', '.join(c.name for c in CATALOGUE)})")
