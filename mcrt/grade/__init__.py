"""Grading harness for the course assignment: ``mcrt grade``.

Image mode grades students' renders of the canonical scene (any renderer,
any language) against the reference, fairly at any sample count >= 16:
pre-checks with their own messages (unreadable files, resolution, NaN,
negative values, gamma, flips, swapped cameras, exposure), a noise-aware
multi-scale bias test, error metrics, and a diagnosis naming the catalogued
bug the image most resembles and where. Code mode runs a student's Python
module through the same checks in a sandboxed subprocess.

API (imported lazily, so ``mcrt --help`` stays fast):

* :func:`load_assignment` -> :class:`Assignment` (``mcrt.grade.assignment``)
* :func:`prepare_context` -> :class:`Context` (``mcrt.grade.expected``)
* :func:`grade_class` -> :class:`ClassResult` (``mcrt.grade.batch``)
* :func:`grade_submission`, :func:`grade_image` -> :class:`StudentResult` (``mcrt.grade.grader``, which runs
  the stages of ``mcrt.grade.stages``; results and points: ``mcrt.grade.scoring``)
* :func:`discover` (``mcrt.grade.submissions``)
* :func:`grade_code` (``mcrt.grade.codemode``), :func:`grade_code_class` (``mcrt.grade.batch``)
* :func:`register` adds ``grade`` to the ``mcrt`` command line (``mcrt.grade.cli``)
"""

from __future__ import annotations

import importlib

_API = {
    "load_assignment": "assignment", "Assignment": "assignment", "AssignmentError": "assignment",
    "prepare_context": "expected", "Context": "expected",
    "grade_class": "batch", "ClassResult": "batch",
    "grade_submission": "grader", "grade_image": "grader", "StudentResult": "scoring", "TestResult": "scoring",
    "discover": "submissions", "Submission": "submissions",
    "grade_code": "codemode", "grade_code_class": "batch",
    "register": "cli", "main": "cli",
}

__all__ = [  # noqa: RUF022 - grouped by module, as _API
    "load_assignment", "Assignment", "AssignmentError", "prepare_context", "Context", "grade_class", "ClassResult",
    "grade_submission", "grade_image", "StudentResult", "TestResult", "discover", "Submission", "grade_code",
    "grade_code_class", "register", "main",
]


def __getattr__(name: str):
    if name in _API:
        return getattr(importlib.import_module(f"mcrt.grade.{_API[name]}"), name)
    raise AttributeError(f"module 'mcrt.grade' has no attribute {name!r}")
