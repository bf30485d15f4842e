"""The package's shape: one import name, no import circle, a MuJoCo-free checker, a docstring per package.

The import graph is read from the source (every import statement, at the top
of a module or inside a function, but not those under ``TYPE_CHECKING``,
which never run) and checked for circles with Tarjan's algorithm on scipy's
strongly connected components, not by importing.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = {"cablecheck": ROOT / "sim", "cablecheck.checker": ROOT / "checker"}


def _modules() -> dict[str, Path]:
    """Every module of the package by its import name (sim/ is cablecheck, checker/ is cablecheck.checker)."""
    out = {}
    for name, folder in FOLDERS.items():
        for path in sorted(folder.rglob("*.py")):
            parts = path.relative_to(folder).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join((name, *parts))] = path
    return out


def _type_checking(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def _imports(path: Path, name: str) -> set[str]:
    """The dotted names a module imports: an ``import``'s names; a ``from`` import's module + each name,
    and its module alone, marked with a trailing dot (a package's submodules import it anyway)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if _type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*up, base] if base else up)
            found.add(base + ".")
            found.update(f"{base}.{a.name}" for a in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(), str(path)))
    return found


def _graph() -> tuple[list[str], dict[str, set[str]]]:
    modules = _modules()
    edges = {}
    for name, path in modules.items():
        deps = set()
        found = _imports(path, name)
        for dotted in found:
            if dotted.endswith("."):   # `from M import a, b`: M itself unless a and b are its submodules
                names = [f for f in found if f.startswith(dotted) and f != dotted and "." not in f[len(dotted):]]
                if names and all(f in modules for f in names):
                    continue
                dotted = dotted[:-1]
            while dotted and dotted not in modules:   # a name inside a module: the module
                dotted = dotted.rpartition(".")[0]
            if dotted and dotted != name:
                deps.add(dotted)
        edges[name] = deps
    return sorted(modules), edges


def circles(names: list[str], edges: dict[str, set[str]]) -> list[list[str]]:
    """The import circles: strongly connected components of more than one module."""
    index = {n: i for i, n in enumerate(names)}
    pairs = np.array([(index[a], index[b]) for a in names for b in edges[a]], dtype=int).reshape(-1, 2)
    graph = coo_array((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(names),) * 2)
    count, label = connected_components(graph, directed=True, connection="strong")
    groups = [[names[i] for i in np.flatnonzero(label == k)] for k in range(count)]
    return [g for g in groups if len(g) > 1]


def test_the_circle_finder_finds_a_circle_and_a_self_free_chain():
    names = ["a", "b", "c", "d"]
    assert circles(names, {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles(names, {"a": {"b"}, "b": {"c"}, "c": set(), "d": {"a"}}) == []


def test_the_graph_reads_relative_function_level_imports_and_skips_type_checking(tmp_path):
    pkg = tmp_path / "p"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    src = ("from typing import TYPE_CHECKING\nfrom . import b\nif TYPE_CHECKING:\n    from .c import X\n"
           "def f():\n    from .d import y\n")
    (pkg / "a.py").write_text(src)
    found = _imports(pkg / "a.py", "p.a")
    assert {"p.", "p.b", "p.d.", "p.d.y"} <= found and not any(x.startswith("p.c") for x in found)


def test_no_import_circle_among_the_packages_modules():
    names, edges = _graph()
    assert len(names) > 100 and any(edges.values())
    assert circles(names, edges) == []


def test_no_checker_module_imports_mujoco():
    names, edges = _graph()
    modules = _modules()
    for name in names:
        if name.startswith("cablecheck.checker"):
            assert not any(d == "mujoco" or d.startswith("mujoco.") for d in _imports(modules[name], name)), name
            assert not any(d.startswith("cablecheck.") and not d.startswith("cablecheck.checker")
                           for d in edges[name]), name


def test_the_checker_imports_without_mujoco_in_a_fresh_interpreter():
    code = ("import sys, pkgutil, importlib, cablecheck.checker as c\n"
            "for m in pkgutil.walk_packages(c.__path__, 'cablecheck.checker.'): importlib.import_module(m.name)\n"
            "print(sorted(n for n in sys.modules if n.split('.')[0] in ('mujoco', 'rerun', 'dask')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"


def test_only_cablecheck_imports_even_from_the_repository_root():
    ok = subprocess.run([sys.executable, "-c", "import cablecheck; print(cablecheck.load_scene.__module__)"],
                        capture_output=True, text=True, cwd=ROOT)
    assert ok.returncode == 0 and ok.stdout.strip() == "cablecheck.scene.load", ok.stderr
    for name in ("sim", "checker"):
        bad = subprocess.run([sys.executable, "-c", f"import {name}"], capture_output=True, text=True, cwd=ROOT)
        assert bad.returncode != 0 and "import cablecheck" in bad.stderr


def test_the_distribution_lists_every_package_folder():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    assert listed == {n for n, p in _modules().items() if p.name == "__init__.py"}


@pytest.mark.parametrize("name", sorted(n for n, p in _modules().items() if p.name == "__init__.py"))
def test_every_package_says_what_it_holds_and_what_it_does_not(name):
    doc = ast.get_docstring(ast.parse(_modules()[name].read_text())) or ""
    assert len(doc.split()) > 15 and any(w in doc for w in (" not ", " no ", "othing")), name


def test_the_public_api_names_resolve():
    import cablecheck

    for name in cablecheck.__all__:
        assert getattr(cablecheck, name) is not None
    with pytest.raises(AttributeError):
        cablecheck.no_such_name


def _deferred_without_a_reason() -> list[str]:
    """Functions of the package that import inside themselves and say nowhere why: no comment on any of
    their import lines, nor on the line above the first."""
    out = []
    for name, path in _modules().items():
        lines = path.read_text().split("\n")
        for fn in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            inner = [n for n in ast.walk(fn) if isinstance(n, (ast.Import, ast.ImportFrom))]
            if not inner:
                continue
            first = min(n.lineno for n in inner)
            said = "#" in lines[first - 2] or any("#" in line for n in inner
                                                  for line in lines[n.lineno - 1:n.end_lineno])
            if not said:
                out.append(f"{path.relative_to(ROOT)}:{first} {fn.name}")
    return out


def test_imports_are_at_the_top_unless_a_line_says_why_not():
    assert _deferred_without_a_reason() == []


def test_no_stage_imports_the_benchmarks_and_no_package_re_exports():
    """Benchmark helpers stay out of the run's way; sim/'s packages hold no facade of re-exported names
    (the checker keeps its own, one room per job; cablecheck's public API loads lazily)."""
    names, edges = _graph()
    for name in names:
        if not name.startswith(("cablecheck.bench", "cablecheck.cli")):
            assert not any(d.startswith("cablecheck.bench") for d in edges[name]), name
    for name, path in _modules().items():
        if path.name == "__init__.py" and path.is_relative_to(FOLDERS["cablecheck"]) and name != "cablecheck":
            tree = ast.parse(path.read_text())
            assert not any(isinstance(n, (ast.Import, ast.ImportFrom)) for n in tree.body), name
