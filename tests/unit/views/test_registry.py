"""Views attached to a Manager from ``cosleec.views`` (issue 29, part 4): the runtime names no view.

:func:`load_view` finds a view by its entry point and says what is wrong with one it cannot
use; :class:`AttachedView` keeps the order a caller needs (found before any Manager,
attached before it starts, closed before it closes, one Manager at a time), built here with
a fake view and fake Managers; :func:`attach` then start then close serves the real web view
and frees its port.
"""

from __future__ import annotations

import ast
import importlib.util
from importlib import metadata
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx
import pytest

import cosleec.runtime
from cosleec.errors import UserError
from cosleec.runtime import ConfigurationError, Manager, VirtualClock
from cosleec.views import registry
from cosleec.views.registry import GROUP, AttachedView, attach, load_view

from .test_web import refused, web_threads

RUNTIME = Path(cosleec.runtime.__file__).parent
TEXT = "def_start event E event A def_end rule_start R1 when E then A within 10 seconds rule_end"


# ---------------------------------------------------------------------- the runtime names no view


def test_no_module_of_the_runtime_names_a_view_or_the_views_package() -> None:
    named = []
    for path in sorted(RUNTIME.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        for word in ("cosleec.views", "load_view", "ViewFactory", "web_url", "self.view", "web="):
            if word in text:
                named.append(f"{path.name}: {word}")
        for node in ast.walk(ast.parse(text)):
            names = [node.id] if isinstance(node, ast.Name) else []
            names += [node.attr] if isinstance(node, ast.Attribute) else []
            names += [node.name] if isinstance(node, ast.ClassDef | ast.FunctionDef) else []
            names += [a.name for a in node.names] if isinstance(node, ast.ImportFrom | ast.Import) else []
            named += [f"{path.name}: {n}" for n in names if n == "web" or "View" in n]
    assert named == []


def test_the_runtime_offers_no_view_and_a_manager_has_none() -> None:
    assert not {"View", "ViewFactory", "load_view", "views"} & set(dir(cosleec.runtime))
    assert importlib.util.find_spec("cosleec.runtime.views") is None
    m = Manager.from_text(TEXT, clock=VirtualClock())
    try:
        assert not hasattr(m, "view") and not hasattr(m, "web_url")
        with pytest.raises(TypeError, match="'web'"):
            Manager.from_text(TEXT, web=0)
    finally:
        m.close()


# ---------------------------------------------------------------------- load_view


def installed(monkeypatch: pytest.MonkeyPatch, value: str) -> None:
    """As if the only view installed were ``fake = value``."""
    point = metadata.EntryPoint(name="fake", value=value, group=GROUP)
    monkeypatch.setattr(
        registry.metadata,
        "entry_points",
        lambda group, name: metadata.EntryPoints([point] if (group, name) == (GROUP, "fake") else []),
    )


def test_load_view_gives_the_factory_of_the_entry_point(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, f"{__name__}:Factory")
    assert load_view("fake") is Factory
    with pytest.raises(ConfigurationError, match="the web view is not installed"):
        load_view("web")  # only "fake" is, now


def test_a_view_that_cannot_be_imported_names_the_module_it_needs(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, "cosleec_no_such_module:serve")
    with pytest.raises(ConfigurationError, match="the fake view cannot be loaded: No module named") as e:
        load_view("fake")
    assert e.value.hint == "install it: pip install 'cosleec[fake]' (it needs cosleec_no_such_module)"


def test_an_entry_point_that_is_not_callable_is_not_a_view_factory(monkeypatch: pytest.MonkeyPatch) -> None:
    installed(monkeypatch, "os:sep")
    with pytest.raises(ConfigurationError, match=r"^the fake view \(os:sep\) is not a view factory$"):
        load_view("fake")


# ---------------------------------------------------------------------- AttachedView, alone


class FakeView:
    def __init__(self, log: list[str], manager: Any, options: object) -> None:
        self.log, self.manager, self.options = log, manager, options
        self.name = getattr(manager, "name", "manager")
        self.url = f"fake://{self.name}/"
        self.closed = 0

    def close(self) -> None:
        self.closed += 1
        self.log.append(f"closed {self.name}")


class Factory:
    """A view factory that logs what it makes."""

    def __init__(self) -> None:
        self.log: list[str] = []
        self.made: list[FakeView] = []

    def __call__(self, manager: Any, options: object) -> FakeView:
        self.log.append(f"made {manager.name} {options}")
        self.made.append(FakeView(self.log, manager, options))
        return self.made[-1]


class FakeManager:
    def __init__(self, name: str, log: list[str], fails: bool = False) -> None:
        self.name, self.log, self.fails = name, log, fails

    def start(self, *, check: bool = True, timer: bool = False) -> None:
        self.log.append(f"start {self.name} check={check} timer={timer}")
        if self.fails:
            raise UserError("cannot start")


@pytest.fixture
def factory(monkeypatch: pytest.MonkeyPatch) -> Factory:
    made = Factory()
    monkeypatch.setattr(registry, "load_view", lambda name: made if name == "fake" else load_view(name))
    return made


def test_a_view_that_is_not_installed_is_said_when_made_before_any_manager() -> None:
    with pytest.raises(ConfigurationError, match="the nope view is not installed") as e:
        AttachedView(0, name="nope")
    assert e.value.hint == "install it: pip install 'cosleec[nope]'"


def test_attach_makes_the_view_with_the_options_and_url_follows_it(factory: Factory) -> None:
    web = AttachedView({"port": 1}, name="fake")
    assert web.url is None and web.view is None and factory.log == []  # nothing made until attached
    m = FakeManager("m", factory.log)
    view = web.attach(m)  # type: ignore[arg-type]
    assert view is factory.made[0] and web.view is view and web.url == "fake://m/"
    assert factory.log == ["made m {'port': 1}"]
    assert web.attach(m) is view  # type: ignore[arg-type]  # the same Manager keeps its view
    assert len(factory.made) == 1


def test_attaching_another_manager_closes_the_first_view_before_making_the_next(factory: Factory) -> None:
    web = AttachedView(8765, name="fake")
    web.attach(FakeManager("one", factory.log))  # type: ignore[arg-type]
    web.attach(FakeManager("two", factory.log))  # type: ignore[arg-type]  # e.g. a lifecycle configure
    assert factory.log == ["made one 8765", "closed one", "made two 8765"]  # the port is free for it
    assert web.url == "fake://two/"


def test_close_stops_the_view_once_and_url_is_none_after(factory: Factory) -> None:
    web = AttachedView(0, name="fake")
    web.attach(FakeManager("m", factory.log))  # type: ignore[arg-type]
    web.close()
    web.close()
    assert factory.made[0].closed == 1 and web.url is None and web.view is None


def test_a_with_block_closes_the_view_even_when_it_raises(factory: Factory) -> None:
    with pytest.raises(RuntimeError), AttachedView(0, name="fake") as web:
        web.attach(FakeManager("m", factory.log))  # type: ignore[arg-type]
        raise RuntimeError
    assert factory.made[0].closed == 1 and web.url is None


def test_start_attaches_before_the_manager_starts_and_passes_its_options(factory: Factory) -> None:
    web = AttachedView(0, name="fake")
    m = FakeManager("m", factory.log)
    assert web.start(m, check=False, timer=True) is m  # type: ignore[arg-type]
    assert factory.log == ["made m 0", "start m check=False timer=True"]
    assert web.url == "fake://m/"


def test_a_start_that_fails_serves_nothing(factory: Factory) -> None:
    web = AttachedView(0, name="fake")
    with pytest.raises(UserError, match="cannot start"):
        web.start(FakeManager("m", factory.log, fails=True))  # type: ignore[arg-type]
    assert factory.log == ["made m 0", "start m check=True timer=False", "closed m"]
    assert web.url is None


def test_an_attached_view_hears_the_records_of_the_start(monkeypatch: pytest.MonkeyPatch) -> None:
    heard: list[str] = []

    def following(manager: Manager, options: object) -> FakeView:  # it subscribes, as the web view does
        manager.subscribe(lambda ev: heard.append(ev.kind))
        return FakeView([], manager, options)

    monkeypatch.setattr(registry, "load_view", lambda name: following)
    web = AttachedView(0, name="fake")
    m = Manager.from_text(TEXT, clock=VirtualClock())
    try:
        web.start(m, check=False)
        assert "options" in heard  # start's own record: the view was there before it
    finally:
        web.close()
        m.close()


# ---------------------------------------------------------------------- the real web view


def test_attach_then_start_then_close_serves_the_web_view_and_frees_the_port() -> None:
    pytest.importorskip("sse_starlette", reason="the web extra is not installed here")
    m = Manager.from_text(TEXT, clock=VirtualClock(), dispatch=False)
    view = attach(m, 0)  # serves from now
    try:
        m.start()
        m.event("E")
        assert view.url.startswith("http://127.0.0.1:")
        state = httpx.get(view.url + "state", timeout=5).json()
        assert [d["rule"] for d in state["decisions"]] == ["R1"]
        port = urlsplit(view.url).port or 0
    finally:
        view.close()
        m.close()
    assert refused(port) and not web_threads()
