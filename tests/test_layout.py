"""The shape of the package: no import cycle, no oversized module or function.

Imports are read from the source (``ast``), not from a running interpreter, so every import
counts wherever it sits: at module level, under ``if TYPE_CHECKING:``, or inside a function. A
lazy import inside a function still ties the two modules together (the loop is only hidden
until that function runs), so it gets no pass; the one kind of lazy import that may stay lazy,
an optional extra (torch, rerun, trimesh), is a third-party package and never an edge between
two hsqbench modules, so no exemption is needed for it.

Sizes: a module at most :data:`MAX_MODULE_LINES` lines; a function at most
:data:`MAX_FUNCTION_LINES` lines of code, counted from its first statement after the docstring
to its last line (a long docstring is documentation, not size).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "hsqbench"
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 60


def module_names(root: Path) -> dict[str, Path]:
    """Dotted name -> file of every module under ``root`` (a package folder)."""
    names = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def _imported(node: ast.AST, module: str, is_package: bool, known: dict[str, Path]) -> set[str]:
    """The modules of ``known`` that one import statement in ``module`` names."""
    if isinstance(node, ast.Import):
        targets = [alias.name for alias in node.names]
    elif isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:  # relative: resolved against the importing module's package
            package = module.split(".") if is_package else module.split(".")[:-1]
            package = package[: len(package) - (node.level - 1)]
            base = ".".join([*package, *([base] if base else [])])
        # `from pkg import name` imports the submodule pkg.name when there is one.
        targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
    else:
        return set()
    found = set()
    for target in targets:
        while target and target not in known:  # `import a.b.c` where c is an attribute
            target = target.rpartition(".")[0]
        if target:
            found.add(target)
    return found


def import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the package modules it imports, wherever in the module the import sits."""
    known = module_names(root)
    graph = {}
    for name, path in known.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        is_package = path.name == "__init__.py"
        edges: set[str] = set()
        for node in ast.walk(tree):
            edges |= _imported(node, name, is_package, known)
        graph[name] = edges - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(component)
    return found


def _describe(component: set[str], graph: dict[str, set[str]]) -> str:
    edges = [f"{a} -> {b}" for a in sorted(component) for b in sorted(graph[a] & component)]
    return "; ".join(edges)


def test_no_module_imports_itself_through_others() -> None:
    graph = import_graph(PACKAGE)
    found = cycles(graph)
    assert not found, "import cycles (move the shared names below both modules): " + " | ".join(
        _describe(c, graph) for c in found
    )


def _write(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root / "pkg"


@pytest.mark.parametrize(
    "import_line",
    [
        "from pkg.b import x",  # module level
        "if TYPE_CHECKING:\n    from pkg.b import x",  # for type hints only
        "def f():\n    from pkg.b import x",  # lazy, inside a function
        "from . import b",  # relative, a submodule
        "import pkg.b.x",  # an attribute of a module
    ],
)
def test_the_cycle_finder_sees_every_kind_of_import(tmp_path, import_line) -> None:
    package = _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/a.py": import_line + "\n",
            "pkg/b.py": "from pkg.sub.c import y\nx = 1\n",
            "pkg/sub/__init__.py": "",
            "pkg/sub/c.py": "from ..a import z\ny = 2\n",
        },
    )
    assert cycles(import_graph(package)) == [{"pkg.a", "pkg.b", "pkg.sub.c"}]


def test_the_cycle_finder_passes_imports_that_go_one_way(tmp_path) -> None:
    package = _write(
        tmp_path,
        {
            "pkg/__init__.py": "from pkg.a import x\n",
            "pkg/a.py": "from pkg.b import y\nimport numpy\nx = 1\n",
            "pkg/b.py": "import os\ny = 2\n",
        },
    )
    graph = import_graph(package)
    assert graph == {"pkg": {"pkg.a"}, "pkg.a": {"pkg.b"}, "pkg.b": set()}
    assert cycles(graph) == []


def _function_lengths(path: Path) -> dict[str, int]:
    """Function name -> lines from its first statement after the docstring to its end."""
    lengths = {}
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        body = node.body
        if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            body = body[1:] or body
        length = node.end_lineno - body[0].lineno + 1
        lengths[node.name] = max(length, lengths.get(node.name, 0))
    return lengths


def test_modules_and_functions_stay_small() -> None:
    too_long = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).as_posix()
        n_lines = len(path.read_text().splitlines())
        if n_lines > MAX_MODULE_LINES:
            too_long.append(f"{rel}: {n_lines} lines (at most {MAX_MODULE_LINES})")
        for name, length in _function_lengths(path).items():
            key = f"{rel}:{name}"
            if length > MAX_FUNCTION_LINES:
                too_long.append(f"{key}: {length} lines (at most {MAX_FUNCTION_LINES})")
    assert not too_long, "split these: " + "; ".join(too_long)
