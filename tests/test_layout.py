"""The package's layout: no import cycles, and every package the source holds is one the install ships."""

from __future__ import annotations

import tomllib
from pathlib import Path

import mcrt

PACKAGE = Path(mcrt.__file__).resolve().parent
ROOT = PACKAGE.parent


def import_graph(roots: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules of the packages ``roots`` (name -> folder) it imports, at module level or inside functions.

    ``from pkg import name`` counts as importing ``pkg`` (its ``__init__``
    runs, and ``name`` may be defined there) and, when ``pkg.name`` is a
    module, that module too.
    """
    import ast

    files = {}
    for package_name, root in roots.items():
        for path in sorted(root.rglob("*.py")):
            parts = (package_name, *path.relative_to(root).with_suffix("").parts)
            files[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                edges |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                edges |= {base} | {f"{base}.{a.name}" for a in node.names}
        graph[name] = {e for e in edges if e in files and e != name}
    return graph


def cycles_through(graph: dict[str, set[str]], prefixes: tuple[str, ...]) -> list[list[str]]:
    """Strongly connected groups of two or more modules (import cycles) that hold a module starting with ``prefixes``."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []

    def visit(v: str) -> None:  # Tarjan
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1 and any(m.startswith(prefixes) for m in group):
                out.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    """No module of mcrt imports, directly or through others, a module that imports it (module or function level)."""
    graph = import_graph({"mcrt": PACKAGE, "mcrt.plugins": ROOT / "plugins"})
    assert "mcrt.grade.batch" in graph and "mcrt.report.run" in graph and "mcrt.plugins.host" in graph
    assert cycles_through(graph, ("mcrt",)) == []
    # The check sees a cycle when there is one: a function-level import back from run to the package.
    graph["mcrt.report.run"] = graph["mcrt.report.run"] | {"mcrt.report"}
    graph["mcrt.report"] = graph["mcrt.report"] | {"mcrt.report.run"}
    assert cycles_through(graph, ("mcrt.grade", "mcrt.report")) == [["mcrt.report", "mcrt.report.run"]]


def _recorded_commands() -> dict[str, str]:
    """reports/<name> -> the mcrt command its committed JSON records (without the program's path)."""
    import json

    def find(d):
        if isinstance(d, dict):
            if isinstance(d.get("command"), str):
                return d["command"]
            for v in d.values():
                if (c := find(v)) is not None:
                    return c
        return None

    out = {}
    for path in sorted((ROOT / "reports").rglob("*.json")):
        command = find(json.loads(path.read_text()))
        if command:
            words = command.split()
            out.setdefault(path.parent.relative_to(ROOT / "reports").as_posix(), " ".join(words[1:]) if words[0].endswith("mcrt") else command)
    return out


def test_mcrt_reports_rebuilds_every_committed_report_with_its_own_command():
    """Every report folder's JSON records the command in mcrt.reports.REPORTS, and REPORTS has no other."""
    from mcrt.reports import REPORTS

    assert _recorded_commands() == {r.name: r.command for r in REPORTS}


def test_the_install_ships_every_package_of_the_source():
    """pyproject.toml lists each folder of mcrt/ with an __init__.py, plugins/ as mcrt.plugins, and reference/ with
    every sub-folder as mcrt.data (package data: the scenes, references and assignments)."""
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    code = {"mcrt"} | {"mcrt." + ".".join(p.parent.relative_to(PACKAGE).parts) for p in PACKAGE.glob("*/**/__init__.py")} | {"mcrt.plugins"}
    data = {"mcrt.data"} | {"mcrt.data." + ".".join(p.relative_to(ROOT / "reference").parts) for p in (ROOT / "reference").rglob("*")
                            if p.is_dir() and p.name not in ("__pycache__", "chunks")}
    assert set(tool["packages"]) == code | data
    assert tool["package-dir"] == {"mcrt.plugins": "plugins", "mcrt.data": "reference"}
    assert set(tool["package-data"]) == data


def test_path_kernel_code_takes_minima_by_select():
    """The modules traced into the path kernels use mcrt.minmax, not Dr.Jit's float minimum, maximum or clip.

    Those lower to llvm.minimum / llvm.maximum, which LLVM's x86 back end
    sometimes scalarises and then cannot select, aborting the process
    (mcrt.minmax's docstring); which kernel it hits changes with unrelated
    edits, so this checks the source rather than one compiled kernel.
    """
    import re

    root = Path(mcrt.__file__).parent
    kernel = ["estimator.py", "geometry.py", "sampling.py", "light.py", "bsdf.py", "camera.py", "host.py", "rng.py", "bidir.py"]
    call = re.compile(r"\bdr\.(minimum|maximum|clip|safe_sqrt)\(")
    found = [f"{name}:{i}" for name in kernel for i, line in enumerate((root / name).read_text().splitlines(), 1)
             if call.search(line)]
    assert not found, f"dr.minimum/maximum/clip/safe_sqrt in path-kernel code: {', '.join(found)}"
