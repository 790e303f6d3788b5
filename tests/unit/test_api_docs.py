"""The API page is readable on the repository and stays in sync with the code; the task page
documents everything `cosleec scaffold` writes; the site is served by one command.

- docs/api.md names every exported name (``cosleec.__all__``, ``cosleec.runtime.__all__``)
  in a table row, and nothing that is not exported; its Manager table names every public
  member of the Manager and nothing the Manager lacks. Its reference from the docstrings is
  in HTML comments (hidden on the repository), which docs/hooks/api_reference.py turns into
  mkdocstrings directives on the site.
- docs/tasks.md names every method, call and module name the scaffold writes, in both styles.
- ``bash scripts/docs`` builds the site and serves it on loopback, with the API reference.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

import cosleec
import cosleec.nodes
import cosleec.runtime
from cosleec.runtime import Manager, RuleSet, VirtualClock, scaffold

ROOT = Path(__file__).resolve().parents[2]
API = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
TASKS = (ROOT / "docs" / "tasks.md").read_text(encoding="utf-8")
RULES = ROOT / "examples" / "assistive_care" / "rules.sleec"  # clauses, and rules with `otherwise`


def sections(page: str) -> dict[str, str]:
    """``## heading`` -> the text under it."""
    parts = re.split(r"^## (.+)$", page, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2], strict=True))


def first_cells(text: str) -> list[str]:
    """The first cell of every table row of ``text`` (not the header or its rule)."""
    rows = [line for line in text.splitlines() if line.startswith("| ")]
    return [
        row.split(" | ")[0][2:]
        for row in rows
        if not set(row) <= set("|- ") and row.split(" | ")[0] != "| name"
    ]


def named(cell: str) -> list[str]:
    """The names a first cell documents: each backquoted name, without ``Manager.`` or arguments."""
    return re.findall(r"`(?:Manager\.)?([A-Za-z_]\w*)", cell)


def test_every_exported_name_is_on_the_api_page_and_only_those() -> None:
    page = sections(API)
    outside = {"The Manager", "ROS nodes"}
    listed = {
        n for title, text in page.items() if title not in outside for c in first_cells(text) for n in named(c)
    }
    exported = set(cosleec.__all__) | set(cosleec.runtime.__all__)
    assert exported - listed == set(), "exported but not on docs/api.md: add a row"
    assert listed - exported == set(), "on docs/api.md but not exported: remove the row"
    nodes = {n for c in first_cells(page["ROS nodes"]) for n in named(c)}
    assert nodes and nodes <= set(cosleec.nodes.__all__)


def test_the_manager_table_names_every_public_member_and_only_real_ones() -> None:
    listed = {n for c in first_cells(sections(API)["The Manager"]) for n in named(c)}
    members = {n for n in vars(Manager) if not n.startswith("_")}
    assert members - listed == set(), "public Manager members missing from docs/api.md's Manager table"
    m = Manager(RuleSet.from_file(RULES), clock=VirtualClock())
    assert {n for n in listed if not hasattr(m, n)} == set(), "docs/api.md names what the Manager has not"


def test_the_api_reference_is_hidden_on_the_repository_and_directives_on_the_site() -> None:
    hook = importlib.util.spec_from_file_location(
        "api_reference", ROOT / "docs" / "hooks" / "api_reference.py"
    )
    assert hook is not None and hook.loader is not None
    module = importlib.util.module_from_spec(hook)
    hook.loader.exec_module(module)
    assert not re.search(r"^:::", API, re.M)  # a bare directive shows as text on the repository
    markers = re.findall(r"^<!-- api: ([\w.]+) -->$", API, re.M)
    assert "cosleec.runtime.Manager" in markers and len(markers) >= 8
    for dotted in markers:  # each names an object mkdocstrings can import
        owner, _, name = dotted.rpartition(".")
        assert hasattr(importlib.import_module(owner), name), dotted
    site = module.on_page_markdown(API, page=None)
    assert re.findall(r"^::: ([\w.]+)$", site, re.M) == markers and "<!-- api:" not in site


def test_every_link_of_the_api_page_reaches_a_heading_or_a_page() -> None:
    slugs = {
        re.sub(r"[^\w\- ]", "", h).strip().lower().replace(" ", "-")
        for h in re.findall(r"^#+ (.+)$", API, re.M)
    }
    for target in re.findall(r"\]\(([^)]+)\)", API):
        if target.startswith("#"):
            assert target[1:] in slugs, target
        elif not target.startswith("http"):
            assert (ROOT / "docs" / target).is_file(), target


# ---------------------------------------------------------------------- what scaffold writes
def _written(style: str) -> tuple[set[str], set[str]]:
    """The functions a scaffold of RULES defines (clause_i and do_Event as one of each) and the
    calls and reads it writes on ``self``, ``node`` and ``decision`` (``self.event``)."""
    tree = ast.parse(scaffold(RuleSet.from_file(RULES), rules_path=str(RULES), style=style))
    defs = {
        re.sub(r"^clause_\d+$", "clause_1", re.sub(r"^do_\w+$", "do_OpenCurtains", n.name))
        for n in ast.walk(tree)
        if isinstance(n, ast.FunctionDef)
    }
    uses = {
        f"{n.value.id}.{n.attr}"
        for n in ast.walk(tree)
        if isinstance(n, ast.Attribute)
        and isinstance(n.value, ast.Name)
        and n.value.id in {"self", "node", "decision"}
    }
    # module and class attributes (TASKS, rule); the entry point's locals are its own business
    bodies = [tree.body, *(c.body for c in tree.body if isinstance(c, ast.ClassDef))]
    names = {
        t.id
        for body in bodies
        for n in body
        if isinstance(n, ast.Assign)
        for t in n.targets
        if isinstance(t, ast.Name)
    }
    return defs | names, uses


@pytest.mark.parametrize("style", ["task", "capability"])
def test_every_method_and_call_scaffold_writes_is_documented_on_the_task_page(style: str) -> None:
    defs, uses = _written(style)
    assert {"install"} <= defs and ("fallback" in defs) == (style == "task")
    for name in sorted(defs | uses):
        assert f"`{name}" in TASKS, f"docs/tasks.md does not document `{name}`, which cosleec scaffold writes"
    assert "`fallback(self, decision)`" in TASKS and "## `fallback`" in TASKS
    assert '`if __name__ == "__main__":`' in TASKS


# ---------------------------------------------------------------------- the site, one command
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _needs_mkdocs() -> None:
    if importlib.util.find_spec("mkdocs") is None:
        if os.environ.get("CI"):
            pytest.fail("mkdocs is not installed: bash scripts/setup --dev installs it")
        pytest.skip("mkdocs is not installed here (bash scripts/setup --dev)")


def test_scripts_docs_serves_the_site_on_loopback_with_the_api_reference() -> None:
    _needs_mkdocs()
    address = f"127.0.0.1:{_free_port()}"
    env = {**os.environ, "PYTHON": sys.executable}
    server = subprocess.Popen(
        ["bash", "scripts/docs", address], cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, start_new_session=True,
    )  # fmt: skip
    try:
        page, deadline = "", time.monotonic() + 120
        while time.monotonic() < deadline and server.poll() is None:
            try:
                with urllib.request.urlopen(f"http://{address}/api/", timeout=5) as answer:
                    page = answer.read().decode("utf-8")
                break
            except OSError:
                time.sleep(0.5)
        assert page, (
            f"not served: {server.stderr.read().decode()[-2000:] if server.poll() is not None else ''}"
        )
        for text in (
            "Manager.reload",
            "Decision.to_json",
            "The Manager",
        ):  # docstrings and the page's own text
            assert text in page
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=30)


def test_scripts_docs_refuses_an_address_off_loopback() -> None:
    done = subprocess.run(
        ["bash", "scripts/docs", "0.0.0.0:8000"], cwd=ROOT, capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 2 and "loopback only" in done.stderr
