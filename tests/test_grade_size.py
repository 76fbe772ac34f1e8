"""Grading stays readable: no function in mcrt/grade/ is longer than about a screen (MAX_LINES)."""

from __future__ import annotations

import ast
from pathlib import Path

import mcrt.grade

GRADE = Path(mcrt.grade.__file__).resolve().parent
#: The longest function allowed, in lines from its ``def`` to its last line (docstring and comments included).
MAX_LINES = 80
#: Functions allowed beyond it, each with the reason; remove an entry when its function is split.
EXCEPTIONS = {
    # The sandbox launcher is being rewritten with mcrt/grade/_sandbox.py (issue 30 leaves it to that work).
    "codemode.py:run_student": "sandbox launcher, rewritten separately",
}


def long_functions(root: Path, limit: int) -> list[str]:
    """'file:function (N lines)' for every function or method under ``root`` longer than ``limit`` lines."""
    out = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    out.append(f"{path.relative_to(root).as_posix()}:{node.name} ({n} lines)")
    return out


def test_no_grading_function_is_longer_than_the_limit():
    found = [f for f in long_functions(GRADE, MAX_LINES) if f.split(" (")[0] not in EXCEPTIONS]
    assert found == [], f"functions over {MAX_LINES} lines in mcrt/grade/ (split them into named steps): {found}"


def test_the_size_check_sees_a_long_function(tmp_path):
    body = "\n".join(f"        x{i} = {i}" for i in range(MAX_LINES))
    (tmp_path / "m.py").write_text(f"def short():\n    return 1\n\n\nclass C:\n    def long(self):\n{body}\n")
    assert long_functions(tmp_path, MAX_LINES) == [f"m.py:long ({MAX_LINES + 1} lines)"]
