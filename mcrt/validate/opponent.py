"""The images a render under test is compared with, and the render under test itself."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from mcrt.film import RenderResult
from mcrt.render import render
from mcrt.scene import Scene
from mcrt.validate.budget import MITSUBA_SEED_BASE, Budget


def render_tested(scene: Scene, b: Budget, seed: int, mutants: Sequence[str] = (), backend: str = "llvm") -> RenderResult:
    """The image under test: mcrt at budget ``b`` with ``seed``, with the catalogued bugs ``mutants`` switched on."""
    sampler = {} if b.pixel_sampler == "independent" else {"pixel_sampler": b.pixel_sampler}
    return render(scene, b.settings(scene), renderer="mcrt", seed=seed, backend=backend, progress=False, mutants=tuple(mutants),
                  **sampler)


class Opponent:
    """The image a render under test is compared with: fresh Mitsuba renders or the committed reference.

    ``kind='mitsuba'``: trial k gets a Mitsuba render with seed
    ``MITSUBA_SEED_BASE + k`` at the budget's spp, cached in memory, so the
    false-alarm and power studies of one process share them.
    ``kind='reference'``: every trial gets the committed reference of the
    budget's (camera, res, max depth) (:func:`mcrt.groundtruth.load_reference`).
    ``kind='reference-floor'``: the same reference, and the render under test
    takes the reference's per-sample variance where its own is lower
    (:func:`mcrt.stats.floor_variance`, the rule of ``mcrt reference verify``).
    """

    KINDS = ("mitsuba", "reference", "reference-floor")

    def __init__(self, scene: Scene, kind: str = "mitsuba", *, backend: str = "llvm"):
        if kind not in self.KINDS:
            raise ValueError(f"against must be one of {', '.join(self.KINDS)}, got {kind!r}")
        self.scene, self.kind, self.backend = scene, kind, backend
        self._cache: dict[tuple, RenderResult] = {}

    def get(self, b: Budget, k: int) -> RenderResult:
        """The opponent of trial ``k`` at budget ``b``."""
        if self.kind != "mitsuba":
            key = ("reference", b.camera, b.res, b.max_depth)
            if key not in self._cache:
                from mcrt.groundtruth import load_reference

                self._cache[key] = load_reference(self.scene, b.camera, b.res, b.max_depth)
            return self._cache[key]
        key = ("mitsuba", b.camera, b.res, b.spp, b.max_depth, k)
        if key not in self._cache:
            self._cache[key] = render(self.scene, b.settings(self.scene), renderer="mitsuba", seed=MITSUBA_SEED_BASE + k,
                                      backend=self.backend, progress=False)
        return self._cache[key]

    def seed(self, k: int) -> int | None:
        """The seed of trial ``k``'s opponent (None: the committed reference)."""
        return MITSUBA_SEED_BASE + k if self.kind == "mitsuba" else None

    def describe(self, b: Budget) -> dict[str, Any]:
        """JSON description of the opponent at budget ``b``."""
        if self.kind == "mitsuba":
            return {"kind": "mitsuba", "spp": b.spp, "seeds": f"{MITSUBA_SEED_BASE} + k (one fresh render per trial)",
                    "integrator": "path"}
        r = self.get(b, 0)
        from mcrt.groundtruth import reference_key

        floor = self.kind == "reference-floor"
        return {"kind": self.kind, "key": reference_key(self.scene.name, b.camera, b.res, b.max_depth), "spp": int(r.spp),
                "mitsuba_version": r.extra.get("mitsuba_version", ""),
                "note": "one committed reference shared by all trials" + (
                    "; the tested render's per-sample variance floored at the reference's" if floor else "")}

    def label(self, b: Budget) -> str:
        if self.kind == "mitsuba":
            return f"independent Mitsuba renders ({b.spp} spp, seed {MITSUBA_SEED_BASE} + k)"
        d = self.describe(b)
        floor = ("; the tested render's per-sample variance raised to the reference's where lower (mcrt.stats.floor_variance)"
                 if self.kind == "reference-floor" else "")
        return f"the committed reference ({d['key']}, {d['spp']} spp){floor}"

    @property
    def policy(self) -> str:
        """The comparison policy (:mod:`mcrt.stats.policy`): the variance floor against ``reference-floor`` only."""
        return "reference-floor" if self.kind == "reference-floor" else "independent"

    def forget(self, keep: Callable[[tuple], bool]) -> None:
        """Drop cached renders whose key fails ``keep`` (bounds memory between phases)."""
        self._cache = {k: v for k, v in self._cache.items() if keep(k)}
