"""What a convergence report renders: renderers, the spp ladder, seeds, presets.

A report is fully described by a :class:`ReportConfig`; the named presets
(:data:`PRESETS`) are starting points that command-line options override.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import asdict, dataclass, replace
from pathlib import Path

@dataclass(frozen=True)
class RendererSpec:
    """One renderer of a report: ``mcrt``, ``mitsuba`` or ``plugin``, optionally with K shadow rays.

    Written ``mcrt`` or ``mcrt:k30`` (K = 30 shadow rays per diffuse vertex;
    without ``:kN`` the report's ``light_samples`` applies). Mitsuba's path
    integrator has no K: it samples the light once per vertex with MIS.
    """

    kind: str
    light_samples: int | None = None

    @classmethod
    def parse(cls, text: str) -> "RendererSpec":
        m = re.fullmatch(r"\s*(mcrt|mitsuba|plugin)\s*(?::\s*k\s*(\d+))?\s*", text, re.IGNORECASE)
        if not m:
            raise ValueError(f"unknown renderer {text!r}: expected mcrt, mitsuba or plugin, optionally with :kN (e.g. mcrt:k30)")
        kind, k = m.group(1).lower(), m.group(2)
        if k is not None and kind == "mitsuba":
            raise ValueError("mitsuba's path integrator has no shadow-ray count: write plain 'mitsuba'")
        if k is not None and int(k) < 1:
            raise ValueError(f"{text!r}: the number of shadow rays must be >= 1")
        return cls(kind, int(k) if k is not None else None)

    @property
    def text(self) -> str:
        return self.kind if self.light_samples is None else f"{self.kind}:k{self.light_samples}"

    @property
    def label(self) -> str:
        """Name in plots and tables: 'mcrt', 'mitsuba', 'mcrt K=30'."""
        return self.kind if self.light_samples is None else f"{self.kind} K={self.light_samples}"

    def shadow_rays(self, default: int) -> int | None:
        """K this renderer uses (None for Mitsuba)."""
        if self.kind == "mitsuba":
            return None
        return self.light_samples if self.light_samples is not None else default


def parse_ladder(text: str) -> tuple[int, ...]:
    """``1,2,4,8`` or ``1..1024`` (powers of two from 1 to 1024) or a mix: ``1..16,100``."""
    out: list[int] = []
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        if ".." in part:
            a, b = (int(x) for x in part.split("..", 1))
            if a < 1 or b < a:
                raise ValueError(f"bad spp range {part!r}: need 1 <= first <= last")
            v = a
            while v <= b:
                out.append(v)
                v *= 2
        else:
            out.append(int(part))
    if not out or any(v < 1 for v in out):
        raise ValueError(f"bad spp ladder {text!r}: need positive sample counts")
    return tuple(sorted(set(out)))


def powers_of_two(lo: int, hi: int) -> tuple[int, ...]:
    return parse_ladder(f"{lo}..{hi}")


def default_cache_dir() -> Path:
    """Where rendered (non-committed) references are cached: $MCRT_CACHE or $XDG_CACHE_HOME/mcrt/report-references."""
    if os.environ.get("MCRT_CACHE"):
        return Path(os.environ["MCRT_CACHE"]) / "report-references"
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mcrt" / "report-references"


@dataclass(frozen=True)
class ReportConfig:
    """Everything that decides a report's numbers (timings aside)."""

    name: str = "canonical"
    preset: str | None = "canonical"
    description: str = ""
    scene: str | None = None  # None: the canonical scene file
    camera: str = "near"
    width: int = 64
    height: int = 64
    spp_ladder: tuple[int, ...] = powers_of_two(1, 1024)
    seeds: tuple[int, ...] = (1, 2, 3)
    renderers: tuple[str, ...] = ("mcrt", "mitsuba")
    max_depth: int = 8
    light_samples: int = 1
    backend: str = "llvm"
    #: Equal-time mode: the first renderer renders the ladder; every other one
    #: renders, at each rung, the spp that takes it the same time (measured
    #: in a calibration render of :meth:`probe_spp` spp each).
    equal_time: bool = False
    calibration_spp: int | None = None  # None: max(2, largest rung // 16)
    #: Efficiency ratios are taken against this renderer (its text, e.g. 'mitsuba').
    baseline: str | None = None
    #: 'auto': the committed Mitsuba reference (mcrt.groundtruth) when there is
    #: one, else a render; 'committed': only that; 'render': always render.
    reference: str = "auto"
    reference_renderer: str = "mitsuba"
    reference_spp: int | None = None  # None: 8 x the largest spp of the ladder
    reference_seed: int = 0
    #: Rungs (spp of the first renderer) shown in the image strip; None: first, middle, last.
    strip_spp: tuple[int, ...] | None = None
    cache_dir: str | None = None
    svg: bool = True

    def specs(self) -> list[RendererSpec]:
        specs = [RendererSpec.parse(r) for r in self.renderers]
        labels = [s.label for s in specs]
        if len(set(labels)) != len(labels):
            raise ValueError(f"renderers listed twice: {', '.join(self.renderers)}")
        return specs

    def baseline_spec(self) -> RendererSpec:
        specs = self.specs()
        if self.baseline:
            want = RendererSpec.parse(self.baseline)
            for s in specs:
                if s == want:
                    return s
            raise ValueError(f"baseline {self.baseline!r} is not among the renderers ({', '.join(self.renderers)})")
        for s in specs:
            if s.kind == "mitsuba":
                return s
        return specs[-1]

    def probe_spp(self) -> int:
        """spp of the untimed calibration render of each renderer."""
        return int(self.calibration_spp) if self.calibration_spp else max(2, max(self.spp_ladder) // 16)

    def ref_spp(self) -> int:
        return int(self.reference_spp) if self.reference_spp else 8 * max(self.spp_ladder)

    def check(self) -> "ReportConfig":
        self.specs()
        self.baseline_spec()
        RendererSpec.parse(self.reference_renderer)
        if self.width < 1 or self.height < 1:
            raise ValueError(f"resolution must be positive, got {self.width}x{self.height}")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"need distinct seeds, got {self.seeds}")
        if self.max_depth < 1 and self.max_depth != -1:
            raise ValueError(f"max depth must be -1 or >= 1, got {self.max_depth}")
        if self.light_samples < 1:
            raise ValueError(f"light samples must be >= 1, got {self.light_samples}")
        if self.reference not in ("auto", "committed", "render"):
            raise ValueError(f"reference must be auto, committed or render, got {self.reference!r}")
        if self.equal_time and len(self.renderers) < 2:
            raise ValueError("equal-time mode needs at least two renderers")
        if self.strip_spp:
            missing = [s for s in self.strip_spp if s not in self.spp_ladder]
            if missing:
                raise ValueError(f"strip spp {missing} not in the ladder {list(self.spp_ladder)}")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, tuple):
                d[k] = list(v)
        return d


def render_seed(spec: RendererSpec, base_seed: int, spp: int) -> int:
    """The seed of one render of the ladder: a 31-bit hash of (renderer, base seed, spp).

    Every (renderer, seed, rung) draws its own streams, so the rungs of one
    seed are independent renders, not prefixes of each other.
    """
    key = f"mcrt.report/{spec.text}/{int(base_seed)}/{int(spp)}".encode()
    return int.from_bytes(hashlib.blake2b(key, digest_size=4).digest(), "little") & 0x7FFFFFFF


#: Seed of the warm-up render (its only job is to compile the kernels).
WARMUP_SEED = 987_654_321


def _course_ladder(spp: int) -> tuple[int, ...]:
    """1, 4, 16, ... (powers of four below spp / 2), then spp itself: 1, 4, 16, 100 for 100 spp."""
    ladder, v = [], 1
    while v < spp / 2:
        ladder.append(v)
        v *= 4
    return tuple(ladder + [spp])


def preset_config(name: str, scene=None) -> ReportConfig:
    """The :class:`ReportConfig` of a named preset (see :data:`PRESETS`)."""
    if name not in PRESETS:
        raise ValueError(f"unknown report preset {name!r} (one of {', '.join(PRESETS)})")
    return PRESETS[name](scene)


def _canonical(scene=None) -> ReportConfig:
    return ReportConfig(
        name="canonical", preset="canonical",
        description="The main job: the canonical scene by every renderer, 64x64, spp 1 to 1024, three seeds, "
                    "against the committed Mitsuba reference.",
        renderers=("mcrt", "mitsuba", "plugin"),
    )


def _quick(scene=None) -> ReportConfig:
    return replace(_canonical(scene), name="quick", preset="quick", spp_ladder=powers_of_two(1, 128), seeds=(1, 2),
                   renderers=("mcrt", "mitsuba"), description="A quick look: 64x64, spp 1 to 128, two seeds, mcrt and Mitsuba.")


def _tiny(scene=None) -> ReportConfig:
    return ReportConfig(name="tiny", preset="tiny", width=16, height=16, spp_ladder=(1, 4, 16), seeds=(1,),
                        renderers=("mcrt", "mitsuba"), reference="render", reference_spp=256,
                        description="A smoke test: 16x16, spp 1, 4, 16, one seed, a 256-spp Mitsuba reference.")


def _course2023(scene=None) -> ReportConfig:
    from mcrt.scene import CANONICAL, load_scene

    scene = scene or load_scene(CANONICAL)
    s = scene.settings("course2023")
    k = s.light_samples
    return ReportConfig(
        name="course2023", preset="course2023",
        description=(f"The 2023 course report's settings ({s.width}x{s.height}, {s.spp} spp, {k} shadow rays, max depth "
                     f"{s.max_depth}) against one shadow ray at equal time: are {k} shadow rays worth it?"),
        camera=s.camera, width=s.width, height=s.height, spp_ladder=_course_ladder(s.spp), seeds=(1,),
        renderers=(f"mcrt:k{k}", "mcrt:k1"), max_depth=s.max_depth, light_samples=1,
        equal_time=True, baseline="mcrt:k1",
        # No committed 800x800 Mitsuba reference exists: a high-spp mcrt render
        # (one shadow ray, 1024 spp) stands in, and its noise is subtracted.
        reference="auto", reference_renderer="mcrt:k1", reference_spp=1024,
        strip_spp=(s.spp,),
    )


PRESETS = {
    "canonical": _canonical,
    "quick": _quick,
    "tiny": _tiny,
    "course2023": _course2023,
}

PRESET_HELP = {
    "canonical": "the main job: near camera, 64x64, spp 1..1024, 3 seeds, mcrt + Mitsuba + plugin",
    "quick": "64x64, spp 1..128, 2 seeds, mcrt + Mitsuba",
    "tiny": "16x16, spp 1,4,16, 1 seed, a 256-spp Mitsuba reference (tests)",
    "course2023": "800x800, 100 spp, 30 shadow rays, max depth 8, against K=1 at equal time (reference: 1024-spp mcrt)",
}
