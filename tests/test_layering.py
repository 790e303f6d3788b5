"""The house guards itself: every import of src/cosleec, function bodies included, checked
against the floors of the architecture (README, "Architecture").

floor 4   cli                         the only place that prints and calls sys.exit
floor 3   ros  demo                   adapters and front ends (ros runs the demo over middleware)
floor 2   nodes  testing              the paper's nodes; public test helpers
floor 1   runtime                     on lang and cop
floor 0   errors  lang  cop           cop imports nothing of ours
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src" / "cosleec"

ALLOWED: dict[str, set[str]] = {
    "": set(),  # the root package: a docstring and the version
    "errors": set(),
    "lang": {"errors"},
    "cop": set(),
    "runtime": {"errors", "lang", "cop"},
    "nodes": {"errors", "lang", "runtime"},
    "testing": {"errors", "lang", "cop", "runtime", "nodes"},
    "demo": {"errors", "lang", "runtime", "nodes", "testing"},
    "ros": {"errors", "lang", "runtime", "nodes", "testing", "demo"},
    "cli": {"errors", "lang", "cop", "runtime", "nodes", "testing", "demo", "ros"},
}
NO_FUNCTION_IMPORTS = {"errors", "lang", "cop", "runtime"}


def modules() -> Iterator[tuple[str, Path]]:
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts.pop()
        yield ".".join(parts), path


def package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def imports(path: Path, module: str) -> Iterator[tuple[str, ast.AST, bool]]:
    """(imported module, node, inside a function body) for every import of ours."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_package = path.name == "__init__.py"

    def visit(node: ast.AST, in_function: bool) -> Iterator[tuple[str, ast.AST, bool]]:
        for child in ast.iter_child_nodes(node):
            inner = in_function or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
            if isinstance(child, ast.Import):
                for alias in child.names:
                    if alias.name.startswith("cosleec"):
                        yield alias.name, child, in_function
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    here = module.split(".") if is_package else module.split(".")[:-1]
                    here = here[: len(here) - (child.level - 1)]
                    base = ".".join([*here, base] if base else here)
                if base.startswith("cosleec"):
                    for alias in child.names:
                        yield f"{base}.{alias.name}" if alias.name != "*" else base, child, in_function
            yield from visit(child, inner)

    yield from visit(tree, False)


def resolve(name: str, known: set[str]) -> str:
    """``cosleec.runtime.Manager`` -> ``cosleec.runtime`` (the longest module prefix)."""
    parts = name.split(".")
    while parts and ".".join(parts) not in known:
        parts.pop()
    return ".".join(parts)


def graph() -> dict[str, set[str]]:
    mods = dict(modules())
    known = set(mods)
    out: dict[str, set[str]] = {m: set() for m in mods}
    for m, path in mods.items():
        for name, _, _ in imports(path, m):
            target = resolve(name, known)
            if target and target != m:
                out[m].add(target)
    return out


def test_imports_point_down() -> None:
    problems = []
    for module, path in modules():
        pkg = package(module)
        if pkg not in ALLOWED:
            problems.append(f"{module}: a module outside every package (the house has no room for it)")
            continue
        for name, node, _ in imports(path, module):
            other = package(name)
            if other != pkg and other not in ALLOWED[pkg]:
                problems.append(f"{module}:{node.lineno} imports {name} ({pkg} -> {other} points up or sideways)")
    assert not problems, "\n".join(problems)


def test_other_packages_use_only_the_face() -> None:
    """`from cosleec.runtime import Manager`, never `from cosleec.runtime.manager import ...`."""
    mods = dict(modules())
    known = set(mods)
    problems = []
    for module, path in mods.items():
        for name, node, _ in imports(path, module):
            target = resolve(name, known)
            pkg = package(module)
            if package(target) != pkg and target.count(".") > 1 and target != "cosleec.lang.ast":
                problems.append(f"{module}:{node.lineno} reaches into {target}")
            leaf = name.rsplit(".", 1)[-1]
            if package(target) != pkg and leaf.startswith("_"):
                problems.append(f"{module}:{node.lineno} takes the private name {name}")
    assert not problems, "\n".join(problems)


def test_no_function_level_imports_in_the_core() -> None:
    problems = [
        f"{module}:{node.lineno} imports {name} inside a function"
        for module, path in modules()
        if package(module) in NO_FUNCTION_IMPORTS
        for name, node, in_function in imports(path, module)
        if in_function
    ]
    assert not problems, "\n".join(problems)


def test_no_import_cycles() -> None:
    g = graph()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def connect(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in g[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(g):
        if v not in index:
            connect(v)
    # a package's face importing its own modules is not a cycle unless a module imports the face back
    assert not cycles, "\n".join(" <-> ".join(c) for c in cycles)


def test_only_the_cli_exits() -> None:
    problems = []
    for module, path in modules():
        if package(module) == "cli":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Name) and node.id == "SystemExit":
                problems.append(f"{module}:{node.lineno} uses SystemExit (raise a UserError instead)")
            if isinstance(node, ast.Attribute) and node.attr == "exit" and getattr(node.value, "id", "") == "sys":
                problems.append(f"{module}:{node.lineno} calls sys.exit")
    assert not problems, "\n".join(problems)
