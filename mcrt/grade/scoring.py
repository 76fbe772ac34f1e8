"""Scoring: a hand-in's points, criterion by criterion, for image and code mode alike.

A :class:`Rubric` holds the criteria (image mode: the assignment's rubric,
:data:`mcrt.grade.assignment.CRITERIA`; code mode: its checks) and records
each one's result; :meth:`Rubric.result` adds them up with the summary of
:func:`mcrt.grade.feedback.summary`. How many of the ``unbiased`` points a
failing bias test loses is :func:`unbiased_loss`: by the kind of mistake,
then by its extent, as a TA would.

Scoring of the ``unbiased`` criterion: no penalised test gives full points;
otherwise :func:`tile_loss` is ``min_loss`` plus the share of the image
covered by penalised tests, each pixel weighted by min(1, |relative effect| /
``full_effect``), capped at all the points; :func:`unbiased_loss` then weighs
the kind of mistake (a major mistake loses at least ``major_loss``, one in
a few pixels only ``minor_loss``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

STATUS_GRADED = "graded"
STATUS_ERROR = "error"
STATUS_TIMEOUT = "timeout"


@dataclass
class TestResult:
    name: str
    title: str
    score: float
    max_score: float
    output: str
    visibility: str = "visible"
    status: str = "passed"  # passed, failed, info, not graded


@dataclass
class StudentResult:
    student: str
    status: str
    score: float
    max_score: float
    tests: list[TestResult]
    summary: str
    notes: list[str] = field(default_factory=list)
    diagnosis: list[dict] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    figures: dict = field(default_factory=dict)  # name -> uint8 image, for feedback
    elapsed: float = 0.0


@dataclass(frozen=True)
class Item:
    """One criterion of a rubric: an image-mode criterion or a code-mode check."""

    name: str
    title: str
    points: float
    visibility: str = "visible"


def image_items(a) -> list[Item]:
    """The image rubric of assignment ``a``."""
    return [Item(c.name, c.title, c.points, c.visibility) for c in a.rubric]


def code_items(a, titles: dict[str, str]) -> list[Item]:
    """The code-mode checks of assignment ``a``, titled by ``titles`` (name -> title)."""
    return [Item(c.name, titles.get(c.name, c.name), c.points, c.visibility) for c in a.code.checks]


class Rubric:
    """Collects results in rubric order; a blocked rubric scores the rest 0."""

    def __init__(self, items: list[Item], *, mode: str = "image"):
        self.items = {i.name: i for i in items}
        self.order = [i.name for i in items]
        self.mode = mode  # 'image' or 'code': the summary's wording (mcrt.grade.feedback.summary)
        self.results: dict[str, TestResult] = {}
        self.blocked: str | None = None

    def _record(self, name: str, status: str, output: str, kept: float) -> None:
        c = self.items[name]
        self.results[name] = TestResult(name, c.title, round(c.points * kept, 4), c.points, output, c.visibility, status)

    def set(self, name: str, status: str, output: str, loss: float = 0.0) -> None:
        """A result losing ``loss`` of the points when failed (0 means all of them); none when passed or info."""
        lost = 1.0 if status == "failed" and loss == 0.0 else loss
        if status in ("passed", "info"):
            lost = 0.0
        self._record(name, status, output, 1.0 - min(max(lost, 0.0), 1.0))

    def credit(self, name: str, fraction: float, output: str) -> None:
        """A result keeping ``fraction`` of the points (a code check's outcome): passed only at 1."""
        self._record(name, "passed" if fraction >= 1.0 else "failed", output, max(0.0, min(1.0, fraction)))

    def not_graded(self, name: str, output: str) -> None:
        c = self.items[name]
        self.results[name] = TestResult(name, c.title, 0.0, c.points, output, c.visibility, "not graded")

    def passed(self, name: str, output: str) -> None:
        self.set(name, "passed", output)

    def failed(self, name: str, output: str, loss: float = 1.0) -> None:
        self.set(name, "failed", output, loss)

    def block(self, reason: str) -> None:
        if self.blocked is None:
            self.blocked = reason

    def finish(self) -> list[TestResult]:
        out = []
        for name in self.order:
            if name in self.results:
                out.append(self.results[name])
            else:
                c = self.items[name]
                why = f"not graded: {self.blocked}" if self.blocked else "not graded"
                out.append(TestResult(c.name, c.title, 0.0, c.points, why, c.visibility, "not graded"))
        return out

    def result(self, student: str, *, headline: str = "", notes=None, diagnosis=None, details=None,
               figures=None) -> StudentResult:
        """The graded result: the tests in rubric order, their total and the summary."""
        from mcrt.grade.feedback import summary

        tests = self.finish()
        score = round(sum(t.score for t in tests), 4)
        max_score = sum(t.max_score for t in tests)
        text = summary(tests, score, max_score, blocked=self.blocked, headline=headline, mode=self.mode)
        return StudentResult(student, STATUS_GRADED, score, max_score, tests, text, list(notes or []),
                             list(diagnosis or []), dict(details or {}), dict(figures or {}))


# --------------------------------------------------------------------------
# The unbiased criterion
# --------------------------------------------------------------------------


def tile_loss(bt, min_loss: float) -> float:
    """Share of the unbiased points the tile tests alone lose (0 when nothing is penalised; module docstring)."""
    if not bt.penalised_any:
        return 0.0
    return float(min(1.0, min_loss + (1.0 - min_loss) * bt.severity))


def wrong_surfaces(bt, th, labels: np.ndarray, label_names) -> list[str]:
    """Surfaces most of whose pixels (``major_coverage``) are off by at least ``full_effect``."""
    off = bt.pixel_effect >= th.full_effect
    out = []
    for k in np.unique(labels):
        sel = labels == k
        if sel.sum() >= 8 and float(np.mean(off[sel])) >= th.major_coverage:
            out.append(label_names[int(k)])
    return out


def _rejected_objects(ex: dict, labels: np.ndarray, n_labels: int) -> np.ndarray:
    """(H, W) the pixels of objects whose own tests (mean or structure, mcrt.grade.objects) are rejected."""
    hit = np.zeros(n_labels, bool)
    if "objects" in ex:
        hit |= np.asarray(ex["objects"]).reshape(n_labels, 3).any(axis=1)
    if "object_structure" in ex:
        hit |= np.asarray(ex["object_structure"]).reshape(n_labels)
    return np.append(hit, False)[np.minimum(labels, n_labels)]


def unbiased_loss(bt, th, labels, label_names, *, registration: bool, filtered: bool,
                  major: str | None = None, patches: np.ndarray | None = None) -> tuple[float, str]:
    """Share of the unbiased points lost, as a TA would: by the kind of mistake, then by its extent.

    ``registration``, ``filtered``: the misregistration and filter findings stand (they are dropped
    where the explanation names another cause); ``major``: what the explanation names where it is a
    major kind of mistake whatever its share of the image (an object missing, a colour, the camera);
    ``patches`` (H, W): the pixels of patches found off together (mcrt.grade.structure), part of the extent.
    """
    from mcrt.grade.feedback import fmt_pct

    ex = bt.extra
    t_loss = tile_loss(bt, th.min_loss) if bt.penalised_any else 0.0
    pix = ex["pixels"].reshape(bt.shape + (3,)).any(axis=2) if "pixels" in ex else np.zeros(bt.shape, bool)
    area = float(np.mean((bt.pixel_effect > 0) | pix | _rejected_objects(ex, labels, len(label_names) - 1)
                         | (patches if patches is not None else False)))
    surfaces = wrong_surfaces(bt, th, labels, label_names) if bt.penalised_any else []
    if registration or surfaces or major:
        what = ("; ".join(surfaces[:3]) + (" look wrong" if len(surfaces) > 1 else " looks wrong") if surfaces
                else major if major else "the camera")
        return max(th.major_loss, t_loss), f"a major mistake ({what}): at least {fmt_pct(th.major_loss)}"
    if filtered:
        return max(th.filter_loss, t_loss), f"a filtered image: at least {fmt_pct(th.filter_loss)}"
    if area <= th.minor_area:
        return th.minor_loss, f"a minor mistake, {fmt_pct(area)} of the image: {fmt_pct(th.minor_loss)}"
    if not bt.penalised_any:
        return min(1.0, th.min_loss + (1.0 - th.min_loss) * area), "wrong pixels over part of the image"
    return t_loss, f"{fmt_pct(th.min_loss)} for any significant bias plus the share of the image it covers"
