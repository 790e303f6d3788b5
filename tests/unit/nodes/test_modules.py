"""Task modules (``--module``, ``--path``): found by name or by file, and every way one can
fail is a user error of its own -- never a traceback, never "not found" for a module that was."""

from __future__ import annotations

import sys
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from cosleec.errors import UserError
from cosleec.ros.run import load_module

INSTALL = "def install(node):\n    node.append('installed')\n"


@pytest.fixture
def cwd(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A fresh current directory; sys.path and the modules imported from it are put back after."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.chdir(tmp_path)
    yield tmp_path
    for name, module in list(sys.modules.items()):
        if str(getattr(module, "__file__", None) or "").startswith(str(tmp_path)):
            del sys.modules[name]


def unique(stem: str = "tasks") -> str:
    return f"{stem}_{uuid.uuid4().hex[:8]}"


def write(directory: Path, name: str, text: str) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    f = directory / f"{name}.py"
    f.write_text(text)
    return f


def refused(name: str, path: list[str] | None = None) -> UserError:
    with pytest.raises(UserError) as info:
        load_module(name, path)
    e = info.value  # no other error chained to it, which the CLI would not show anyway
    assert e.__cause__ is None and (e.__context__ is None or e.__suppress_context__)
    return e


# ---------------------------------------------------------------------- found
def test_a_module_in_the_current_directory_is_found(cwd: Path) -> None:
    name = unique()
    write(cwd, name, INSTALL)
    module = load_module(name)
    calls: list[str] = []
    module.install(calls)
    assert calls == ["installed"] and Path(module.__file__).parent == cwd
    assert sys.path[0] == str(cwd)


def test_a_path_directory_comes_before_the_current_directory(cwd: Path) -> None:
    name = unique()
    write(cwd, name, INSTALL + "WHERE = 'cwd'\n")
    write(cwd / "robot", name, INSTALL + "WHERE = 'robot'\n")
    assert load_module(name, ["robot"]).WHERE == "robot"  # a relative --path: from the cwd
    assert sys.path[:2] == [str(cwd / "robot"), str(cwd)]


def test_path_directories_are_searched_in_order_and_stay_for_later_imports(cwd: Path) -> None:
    name, helper = unique(), unique("helper")
    write(cwd / "a", name, f"def install(node):\n    import {helper}\n    node.append({helper}.X)\n")
    write(cwd / "b", helper, "X = 'from b'\n")
    module = load_module(name, [str(cwd / "a"), str(cwd / "b")])
    calls: list[str] = []
    module.install(calls)  # imports its helper only now, after load_module returned
    assert calls == ["from b"]
    assert sys.path[:3] == [str(cwd / "a"), str(cwd / "b"), str(cwd)]


def test_a_module_of_a_package_is_found(cwd: Path) -> None:
    pkg = unique("pkg")
    write(cwd / "lib" / pkg, "__init__", "")
    write(cwd / "lib" / pkg, "tasks", INSTALL)
    assert callable(load_module(f"{pkg}.tasks", ["lib"]).install)


def test_a_python_file_is_imported_from_its_file_with_its_directory_first(cwd: Path) -> None:
    name, helper = unique(), unique("helper")
    write(
        cwd / "robot",
        name,
        f"from __future__ import annotations\nfrom dataclasses import dataclass\nimport {helper}\n\n"
        "@dataclass\nclass Task:\n    speed: float = 0.5\n\n" + INSTALL,
    )
    write(cwd / "robot", helper, "")
    module = load_module(f"robot/{name}.py")
    assert module.__file__ == str(cwd / "robot" / f"{name}.py") and module.Task().speed == 0.5
    assert sys.modules[name] is module  # imported once: `import <name>` elsewhere gets this one
    assert load_module(f"robot/{name}.py") is module
    assert sys.path[0] == str(cwd / "robot")


def test_a_file_given_by_an_absolute_path_or_from_home(cwd: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    name = unique()
    f = write(cwd / "home", name, INSTALL)
    assert callable(load_module(str(f)).install)
    monkeypatch.setenv("HOME", str(cwd / "home"))
    del sys.modules[name]
    assert load_module(f"~/{name}.py").__file__ == str(f)


# ---------------------------------------------------------------------- not found
def test_a_module_that_is_not_there_is_not_found(cwd: Path) -> None:
    e = refused("no_such_tasks_module", ["extra"])
    assert str(e).startswith("no task module 'no_such_tasks_module'")
    assert f"looked in {cwd / 'extra'}, {cwd} and on the Python path" in e.hint and "--path" in e.hint


def test_a_module_of_a_package_that_is_not_there_is_not_found(cwd: Path) -> None:
    assert str(refused("no_such_pkg_xyz.tasks")).startswith("no task module 'no_such_pkg_xyz.tasks'")


def test_a_file_that_is_not_there_is_not_found(cwd: Path) -> None:
    e = refused("robot/tasks.py")
    assert e.message == f"no task module file 'robot/tasks.py' (looked for {cwd / 'robot' / 'tasks.py'})"


@pytest.mark.parametrize("name", ["my-tasks", ".tasks", "", "tasks..x"])
def test_a_name_that_is_neither_a_module_nor_a_file_says_so(cwd: Path, name: str) -> None:
    assert "is neither a module name" in str(refused(name))


def test_a_file_named_like_a_module_already_loaded_must_be_renamed(cwd: Path) -> None:
    write(cwd, "json", INSTALL)
    e = refused("json.py")
    assert "would be the module 'json', but a module of that name is already loaded" in str(e)
    assert e.hint == "rename json.py" and sys.modules["json"].__file__ != str(cwd / "json.py")


# ---------------------------------------------------------------------- found, but failing
def test_an_import_inside_the_module_that_fails_is_not_not_found(cwd: Path) -> None:
    name = unique()
    f = write(cwd, name, "import os\nimport no_such_dependency_xyz\n" + INSTALL)
    e = refused(name)
    assert e.message == (
        f"task module {name!r} was found, but one of its own imports failed: "
        "ModuleNotFoundError: No module named 'no_such_dependency_xyz'"
    )
    assert e.where == f"{f}:2" and "install what it imports" in e.hint
    assert e.hint != refused("no_such_tasks_module").hint


def test_a_from_import_inside_the_module_that_fails(cwd: Path) -> None:
    name = unique()
    f = write(cwd, name, "from os import no_such_name\n" + INSTALL)
    for given in (name, f"{name}.py"):
        e = refused(given)
        assert "was found, but one of its own imports failed: ImportError: cannot import name" in str(e)
        assert e.where == f"{f}:1"
        assert name not in sys.modules  # a failed import leaves nothing half-made behind


@pytest.mark.parametrize("as_file", [False, True])
def test_a_syntax_error_in_the_module_says_where(cwd: Path, as_file: bool) -> None:
    name = unique()
    f = write(cwd, name, INSTALL + "def broken(:\n")
    e = refused(f"{name}.py" if as_file else name)
    assert str(e).startswith(
        f"task module '{name}{'.py' if as_file else ''}' was found but cannot be imported: SyntaxError"
    )
    assert e.where.startswith(f"{f}:3:") and e.hint.startswith("fix the syntax at")


def test_a_syntax_error_in_a_module_it_imports_names_that_file(cwd: Path) -> None:
    name, helper = unique(), unique("helper")
    write(cwd, name, f"import {helper}\n" + INSTALL)
    h = write(cwd, helper, "x = = 1\n")
    assert refused(name).where.startswith(f"{h}:1:")


@pytest.mark.parametrize(
    ("code", "what"),
    [("raise RuntimeError('no robot')", "RuntimeError"), ("raise SystemExit(2)", "SystemExit")],
)
def test_an_exception_in_the_modules_top_level_code(cwd: Path, code: str, what: str) -> None:
    name = unique()
    f = write(cwd, name, "x = 1\n" + code + "\n" + INSTALL)
    e = refused(name)
    assert str(e).startswith(f"task module {name!r} was found, but raised {what} while being imported")
    assert e.where == f"{f}:2" and "install(node)" in e.hint


# ---------------------------------------------------------------------- install(node)
@pytest.mark.parametrize(("body", "extra"), [("X = 1\n", ""), ("install = 3\n", "`install` here is a int")])
def test_a_module_without_a_callable_install_shows_the_signature(cwd: Path, body: str, extra: str) -> None:
    name = unique()
    f = write(cwd, name, body)
    e = refused(name)
    assert e.message == f"task module {name!r} has no install(node) function"
    assert "def install(node: TaskNode) -> None:" in e.hint and extra in e.hint and e.where == str(f)


def test_a_missing_import_whose_name_starts_the_modules_name_is_still_inside_it(cwd: Path) -> None:
    dep = unique("dep")
    write(cwd, f"{dep}_tasks", f"import {dep}\n" + INSTALL)  # `dep` is missing, `dep_tasks` is there
    assert "was found, but one of its own imports failed" in str(refused(f"{dep}_tasks"))
