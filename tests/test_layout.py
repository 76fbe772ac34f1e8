"""The package's layout: layers that import only downwards, no import cycles, and every package the source holds is one
the install ships."""

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
    assert "mcrt.grade.batch" in graph and "mcrt.convergence.run" in graph and "mcrt.plugins.host" in graph
    assert cycles_through(graph, ("mcrt",)) == []
    # The check sees a cycle when there is one: a function-level import back from run to the package.
    graph["mcrt.convergence.run"] = graph["mcrt.convergence.run"] | {"mcrt.convergence"}
    graph["mcrt.convergence"] = graph["mcrt.convergence"] | {"mcrt.convergence.run"}
    assert cycles_through(graph, ("mcrt.grade", "mcrt.convergence")) == [["mcrt.convergence", "mcrt.convergence.run"]]


#: The layers of mcrt, lowest first: (name, rank, module prefixes). A module may import modules of its own rank
#: and below, never above. Each module belongs to the layer of its longest matching prefix. The README's
#: Architecture section mirrors this table.
LAYERS = (
    ("foundation", 0, ("mcrt.llvm", "mcrt.exitcodes", "mcrt.minmax", "mcrt.srgb", "mcrt.util")),
    ("renderer core", 1, ("mcrt", "mcrt.scene", "mcrt.camera", "mcrt.geometry", "mcrt.bsdf", "mcrt.light",
                          "mcrt.sampling", "mcrt.rng", "mcrt.options", "mcrt.estimator", "mcrt.film", "mcrt.tracer",
                          "mcrt.host", "mcrt.mutants", "mcrt.precision", "mcrt.samplers")),
    ("renderers", 2, ("mcrt.render", "mcrt.bidir", "mcrt.plugins", "mcrt.mitsuba_scene", "mcrt.tricks.adaptive",
                      "mcrt.tricks.aov", "mcrt.tricks.denoise", "mcrt.closed_form")),
    ("statistics and I/O", 2, ("mcrt.stats", "mcrt.image_files", "mcrt.metrics", "mcrt.compare", "mcrt.groundtruth",
                               "mcrt.provenance")),
    ("studies and reports", 3, ("mcrt.convergence", "mcrt.validate", "mcrt.hardcases", "mcrt.tricks", "mcrt.bench",
                                "mcrt.bench_limits", "mcrt.bench_page", "mcrt.threeway", "mcrt.validate_integrator",
                                "mcrt.rebuild_reports", "mcrt.pytest_plugin", "mcrt.sampler_study", "mcrt.msuite")),
    ("grading and command line", 4, ("mcrt.grade", "mcrt.cli")),
)


def layer_of(module: str, layers=LAYERS) -> tuple[str, int] | None:
    """(layer name, rank) of ``module``: the layer of its longest matching prefix; None where no prefix matches.

    The package itself ("mcrt", its __init__) names only itself: a new module must be placed in a layer.
    """
    best = None
    for name, rank, prefixes in layers:
        for p in prefixes:
            below = "." in p and module.startswith(p + ".")  # a top-level name covers no module below it
            if (module == p or below) and (best is None or len(p) > best[2]):
                best = (name, rank, len(p))
    return best[:2] if best else None


def upward_imports(graph: dict[str, set[str]], layers=LAYERS) -> list[str]:
    """'a (layer) imports b (higher layer)' for every import of a module from a layer above its own."""
    out = []
    for a in sorted(graph):
        la = layer_of(a, layers)
        for b in sorted(graph[a]):
            lb = layer_of(b, layers)
            if la and lb and lb[1] > la[1]:
                out.append(f"{a} ({la[0]}) imports {b} ({lb[0]})")
    return out


def _mcrt_graph(package: Path = PACKAGE, plugins: Path = ROOT / "plugins") -> dict[str, set[str]]:
    return import_graph({"mcrt": package, "mcrt.plugins": plugins})


def test_every_module_has_a_layer():
    """A new module is placed in LAYERS before it lands (the test names it)."""
    assert [m for m in sorted(_mcrt_graph()) if layer_of(m) is None] == []


def test_no_layer_imports_a_higher_one():
    """The renderer core imports no renderer, study, report or grader; only the command line and grading are on top."""
    graph = _mcrt_graph()
    assert "mcrt.tracer" in graph and "mcrt.plugins.integrator" in graph and "mcrt.grade.grader" in graph
    assert upward_imports(graph) == []
    # The check sees an upward import: the core asking a study for its options, as it once did.
    graph["mcrt.tracer"] = graph["mcrt.tracer"] | {"mcrt.tricks.study"}
    assert upward_imports(graph) == ["mcrt.tracer (renderer core) imports mcrt.tricks.study (studies and reports)"]


def test_layer_check_finds_an_import_planted_in_a_copy_of_the_source(tmp_path):
    """The whole chain (files, ast, graph, layers) on a copy of the package with one function-level upward import."""
    import shutil

    copy = tmp_path / "mcrt"
    shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert upward_imports(_mcrt_graph(copy)) == []
    camera = copy / "camera.py"
    camera.write_text(camera.read_text() + "\n\ndef _planted():\n    from mcrt.grade import grader  # noqa: F401\n")
    assert upward_imports(_mcrt_graph(copy)) == [
        "mcrt.camera (renderer core) imports mcrt.grade (grading and command line)",
        "mcrt.camera (renderer core) imports mcrt.grade.grader (grading and command line)",
    ]


def test_layer_lookup_takes_the_longest_prefix():
    """On a synthetic table: a submodule listed apart from its package gets its own layer; the top-level package
    names only itself, so a module nobody placed has no layer (and test_every_module_has_a_layer names it)."""
    layers = (("low", 0, ("p.a",)), ("high", 1, ("p", "p.b")))
    assert layer_of("p.a.x", layers) == ("low", 0) and layer_of("p.b.y", layers) == ("high", 1)
    assert layer_of("p", layers) == ("high", 1) and layer_of("p.c", layers) is None
    assert layer_of("q", layers) is None
    assert upward_imports({"p.a.x": {"p.b"}, "p.b": {"p.a.x"}}, layers) == ["p.a.x (low) imports p.b (high)"]


def test_the_readme_architecture_section_names_every_layer():
    """README's Architecture section mirrors LAYERS: each layer by name, in order."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("\n## Architecture"):]
    section = section[:section.index("\n## ", 1)] if "\n## " in section[1:] else section
    positions = [section.find(name) for name, _, _ in LAYERS]
    assert -1 not in positions and positions == sorted(positions), positions


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
    """Every report folder's JSON records the command in mcrt.rebuild_reports.REPORTS, and REPORTS has no other."""
    from mcrt.rebuild_reports import REPORTS

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
