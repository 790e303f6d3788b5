"""The wheel and the sdist a user installs: checked by twine, and the wheel run from a fresh
venv outside the repository (``cosleec --version``, ``demo``, ``check``, ``lsp``, the
library), with the files users need shipped in it: the grammars, the demo, the web assets,
the TextMate grammar and the definitions of ``cosleec_interfaces``, each equal to its source.
"""

from __future__ import annotations

import subprocess
import sys
import tarfile
import tomllib
import zipfile
from pathlib import Path

from tests.package.conftest import ROOT, Dist, Installed, lsp_messages, read_lsp

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
VERSION = PYPROJECT["project"]["version"]
INTERFACES = ROOT / "interfaces" / "cosleec_interfaces"
GRAMMAR = ROOT / "editors" / "vscode" / "syntaxes" / "sleec.tmLanguage.json"


def _tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` (links followed), by its path relative to ``root``."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_twine_check_passes_for_the_wheel_and_the_sdist(dist: Dist) -> None:
    p = subprocess.run(
        [sys.executable, "-m", "twine", "check", "--strict", str(dist.wheel), str(dist.sdist)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert p.stdout.count("PASSED") == 2, p.stdout


def test_the_license_is_apache_2_and_ships_in_both(dist: Dist) -> None:
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "Apache License" in text and "Version 2.0, January 2004" in text
    assert "END OF TERMS AND CONDITIONS" in text  # the full text, not a notice
    with zipfile.ZipFile(dist.wheel) as w:
        meta = w.read(f"cosleec-{VERSION}.dist-info/METADATA").decode()
        shipped = w.read(f"cosleec-{VERSION}.dist-info/licenses/LICENSE").decode()
    assert "License-Expression: Apache-2.0" in meta and "License-File: LICENSE" in meta
    assert shipped == text
    with tarfile.open(dist.sdist) as t:
        member = t.extractfile(f"cosleec-{VERSION}/LICENSE")
        assert member is not None and member.read().decode() == text


def test_the_sdist_carries_the_shipped_sources(dist: Dist) -> None:
    with tarfile.open(dist.sdist) as t:
        names = set(t.getnames())
        link = [m.name for m in t.getmembers() if m.issym() or m.islnk()]
    base = f"cosleec-{VERSION}/src/cosleec"
    assert f"{base}/editors/sleec.tmLanguage.json" in names
    for rel in _tree(INTERFACES):
        assert f"{base}/ros/share/cosleec_interfaces/{rel}" in names, rel
    assert not link, f"links in the sdist (they must be files): {link}"


def test_the_wheel_installed_outside_the_repository_runs(installed: Installed) -> None:
    p = installed.run(installed.cosleec, "--version")
    assert p.returncode == 0 and p.stdout.strip() == f"cosleec {VERSION}", p.stdout + p.stderr
    p = installed.run(
        installed.python,
        "-c",
        "from cosleec import Manager; import cosleec, sys; print(cosleec.__file__); print(Manager.__module__)",
    )
    assert p.returncode == 0, p.stderr
    where = Path(p.stdout.splitlines()[0])
    assert where.is_relative_to(installed.root / "venv"), f"cosleec imported from {where}, not the fresh venv"
    assert not where.resolve().is_relative_to(ROOT)


def test_the_demo_runs_from_the_wheel(installed: Installed) -> None:
    p = installed.run(installed.cosleec, "demo")
    assert p.returncode == 0, p.stderr
    assert "cosleec demo: an assistive-care robot under SLEEC rules" in p.stdout
    assert "32 decisions, 2 violations, 1 refused actions, 0 obligations outstanding" in p.stdout
    assert str(installed.root / "venv") in p.stdout  # the rules it read are the shipped ones


def test_check_reads_a_shipped_example(installed: Installed) -> None:
    rules = installed.package_dir() / "demo" / "assistive_care" / "rules.sleec"
    p = installed.run(installed.cosleec, "check", rules)
    assert p.returncode == 0, p.stdout + p.stderr
    assert f"{rules}: ok" in p.stdout


def test_the_language_server_initializes_and_shuts_down(installed: Installed) -> None:
    request = lsp_messages(
        {
            "jsonrpc": "2.0",
            "id": 1,
            "method": "initialize",
            "params": {"processId": None, "rootUri": None, "capabilities": {}},
        },
        {"jsonrpc": "2.0", "method": "initialized", "params": {}},
        {"jsonrpc": "2.0", "id": 2, "method": "shutdown", "params": None},
        {"jsonrpc": "2.0", "method": "exit", "params": None},
    )
    p = subprocess.run(
        [installed.cosleec, "lsp"],
        input=request,
        capture_output=True,
        env=installed.env,
        cwd=installed.cwd,
        timeout=60,
    )
    assert p.returncode == 0, p.stderr.decode()
    replies = {m.get("id"): m for m in read_lsp(p.stdout) if "id" in m}
    init = replies[1]["result"]
    assert isinstance(init, dict) and init["serverInfo"]["name"] == "cosleec"
    assert init["capabilities"]["hoverProvider"], init["capabilities"]
    assert "result" in replies[2] and replies[2]["result"] is None


def test_the_wheel_ships_the_textmate_grammar_and_the_interfaces(installed: Installed) -> None:
    pkg = installed.package_dir()
    assert (pkg / "editors" / "sleec.tmLanguage.json").read_bytes() == GRAMMAR.read_bytes()
    shipped = _tree(pkg / "ros" / "share" / "cosleec_interfaces")
    assert shipped == _tree(INTERFACES), (
        "the wheel's cosleec_interfaces differ from interfaces/cosleec_interfaces"
    )
    assert any(k.startswith("srv/") for k in shipped) and "package.xml" in shipped


def test_the_wheel_ships_the_grammars_the_demo_and_the_web_assets(installed: Installed) -> None:
    pkg = installed.package_dir()
    src = ROOT / "src" / "cosleec"
    for rel in ("lang/grammar", "demo/assistive_care", "views/static"):
        data = {k: v for k, v in _tree(src / rel).items() if not k.endswith((".py", ".pyc"))}
        assert data and data == {
            k: v for k, v in _tree(pkg / rel).items() if not k.endswith((".py", ".pyc"))
        }, rel
    assert (pkg / "py.typed").is_file()


def test_ros2_without_ros_names_the_extra_and_the_setup_command(installed: Installed) -> None:
    for args in (
        ("ros2", "demo"),
        ("ros2", "manager", installed.package_dir() / "demo/assistive_care/rules.sleec"),
    ):
        p = installed.run(installed.cosleec, *args)
        assert p.returncode == 1, p.stderr
        assert "ROS 2 (rclpy) is not available in this Python environment" in p.stderr
        assert "pip install 'cosleec[ros2]'" in p.stderr and "cosleec ros2 setup" in p.stderr
        assert "Traceback" not in p.stderr and ".venv-ros2" not in p.stderr.splitlines()[0]
    p = installed.run(installed.cosleec, "ros2", "setup")
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "the ROS 2 wheels and rosidl's build-time wheels are not installed" in p.stderr
    assert "pip install 'cosleec[ros2]'" in p.stderr


def test_the_declared_dependencies_are_all_the_fresh_venv_has(installed: Installed) -> None:
    # pip itself checks the installed requirements; and a module the dev venv has but cosleec
    # does not declare (the docs' mkdocs, say) cannot be imported in the fresh venv
    p = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(installed.python), "check"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    p = installed.run(installed.python, "-c", "import mkdocs")
    assert p.returncode == 1 and "No module named 'mkdocs'" in p.stderr
