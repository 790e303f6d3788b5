"""The house guards itself: every import of src/cosleec, function bodies included, checked
against the floors of the architecture (docs/development.md, "Architecture").

floor 4   cli                         the only place that prints and calls sys.exit
floor 3   ros  demo  views  lsp       adapters and front ends (ros runs the demo over middleware; views draw;
                                      lsp serves editors)
floor 2   nodes  testing              the paper's nodes; public test helpers
floor 1   runtime  repair             runtime on lang and cop; repair on analysis
floor 0   errors  bulk  records  lang  cop     cop imports nothing of ours
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src" / "cosleec"

ALLOWED: dict[str, set[str]] = {
    "": {"errors", "runtime"},  # the root package: the version, and the short form (lazy)
    "records": {"errors"},  # the audit records: runtime writes them, semantics reads them
    "errors": set(),
    "bulk": set(),
    "lang": {"errors", "bulk"},
    "cop": set(),
    "semantics": {"errors", "bulk", "lang", "records"},
    "analysis": {"errors", "records", "bulk", "lang", "semantics"},
    "repair": {"errors", "records", "bulk", "lang", "semantics", "analysis"},
    "runtime": {"errors", "bulk", "lang", "records", "cop"},
    "nodes": {"errors", "records", "lang", "runtime"},
    "testing": {"errors", "records", "lang", "cop", "runtime", "nodes"},
    "bt": {"errors", "records", "lang", "runtime"},  # behaviour trees on py_trees (the bt extra); ROS-free
    "views": {"errors", "records", "lang", "semantics", "analysis", "runtime", "nodes"},
    "lsp": {"errors", "records", "lang", "semantics", "analysis", "repair"},
    "demo": {"errors", "records", "lang", "runtime", "nodes", "testing"},
    "ros": {"errors", "records", "lang", "runtime", "nodes", "testing", "demo"},
    "cli": {
        "errors",
        "records",
        "lang",
        "cop",
        "semantics",
        "analysis",
        "repair",
        "runtime",
        "nodes",
        "testing",
        "views",
        "lsp",
        "demo",
        "ros",
    },
}
NO_FUNCTION_IMPORTS = {"errors", "lang", "cop", "semantics", "analysis", "repair", "runtime"}


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
                    if alias.name == "cosleec" or alias.name.startswith("cosleec."):
                        yield alias.name, child, in_function
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    here = module.split(".") if is_package else module.split(".")[:-1]
                    here = here[: len(here) - (child.level - 1)]
                    base = ".".join([*here, base] if base else here)
                if base == "cosleec" or base.startswith("cosleec."):  # not cosleec_interfaces
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
        for line, name in references(path, module):
            other = package(name)
            if other != pkg and other not in ALLOWED[pkg]:
                problems.append(f"{module}:{line} imports {name} ({pkg} -> {other} points up or sideways)")
    assert not problems, "\n".join(problems)


def test_other_packages_use_only_the_face() -> None:
    """`from cosleec.runtime import Manager`, never `from cosleec.runtime.manager import ...`,
    `import cosleec.runtime.manager`, `cosleec.runtime.manager.X` through an attribute chain,
    or `importlib.import_module("cosleec.runtime.manager")`."""
    mods = dict(modules())
    problems = []
    for module, path in mods.items():
        pkg = package(module)
        for where, name in references(path, module):
            parts = name.split(".")
            other = parts[1] if len(parts) > 1 else ""
            if other == pkg or not other:
                continue
            face = f"cosleec.{other}"
            if name == face or (name.startswith(face + ".") and name[len(face) + 1 :].count(".") == 0):
                leaf = parts[-1]
                if f"{face}.{leaf}" in mods and not _exported(face, leaf, mods):
                    problems.append(
                        f"{module}:{where} takes the module {name}, which its face does not export"
                    )
                elif leaf.startswith("_"):
                    problems.append(f"{module}:{where} takes the private name {name}")
                continue
            problems.append(f"{module}:{where} reaches past the face of {face}: {name}")
    assert not problems, "\n".join(problems)


def _exported(face: str, leaf: str, mods: dict[str, Path]) -> bool:
    """Does the package face list ``leaf`` (a submodule such as ``lang.ast``) in its ``__all__``?"""
    tree = ast.parse(mods[face].read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets):
            return leaf in ast.literal_eval(node.value)
    return False


def references(path: Path, module: str) -> Iterator[tuple[int, str]]:
    """Every name of ours a module uses: imports (``from X import y`` gives ``X.y``), dotted
    attribute chains starting at ``cosleec``, and literal ``importlib.import_module`` /
    ``__import__`` targets."""
    for name, node, _ in imports(path, module):
        if isinstance(node, ast.ImportFrom):
            yield node.lineno, name  # `from cosleec.lang.ast import Span` stays cosleec.lang.ast.Span
        else:
            yield node.lineno, name
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Attribute) and not isinstance(getattr(node, "ctx", None), ast.Store):
            text = ast.unparse(node)
            if text.startswith("cosleec.") and text.count(".") >= 2:
                yield node.lineno, ".".join(text.split(".")[:3])
        if isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            fn = ast.unparse(node.func)
            target = node.args[0].value
            if fn in ("importlib.import_module", "import_module", "__import__") and str(target).startswith(
                "cosleec"
            ):
                yield node.lineno, str(target)


def test_no_module_takes_another_modules_private_names() -> None:
    problems = [
        f"{module}:{node.lineno} takes the private name {name}"
        for module, path in modules()
        for name, node, _ in imports(path, module)
        if isinstance(node, ast.ImportFrom)
        and name.rsplit(".", 1)[-1].startswith("_")
        and not name.rsplit(".", 1)[-1].startswith("__")
    ]
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
        tree = ast.parse(path.read_text(encoding="utf-8"))
        caught = {  # catching a SystemExit (a user's module that calls sys.exit) is not exiting
            id(n)
            for h in ast.walk(tree)
            if isinstance(h, ast.ExceptHandler) and h.type
            for n in ast.walk(h.type)
        }
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Name)
                and node.id in ("SystemExit", "exit", "quit")
                and id(node) not in caught
            ):
                problems.append(f"{module}:{node.lineno} uses {node.id} (raise a UserError instead)")
            if (
                isinstance(node, ast.Attribute)
                and node.attr in ("exit", "_exit")
                and getattr(node.value, "id", "")
                in (
                    "sys",
                    "os",
                )
            ):
                problems.append(f"{module}:{node.lineno} calls {ast.unparse(node)}")
            if (
                isinstance(node, ast.ImportFrom)
                and node.module in ("sys", "os")
                and any(a.name in ("exit", "_exit") for a in node.names)
            ):
                problems.append(f"{module}:{node.lineno} imports exit from {node.module}")
    assert not problems, "\n".join(problems)
