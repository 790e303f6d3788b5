"""`cosleec scaffold` on the whole corpus: for every file that checks clean, the module it
writes imports, and bound to a Manager it passes the completeness check as it is; on the
examples it is also clean for ruff (the project's configuration) and `mypy --strict`."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from cosleec.errors import UserError
from cosleec.runtime import Manager, RuleSet, VirtualClock
from cosleec.runtime.scaffold import scaffold
from cosleec.testing import corpus_files

ROOT = Path(__file__).resolve().parents[2]
FILES = corpus_files()


def load(path: Path, name: str) -> object:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("style", ["task", "capability"])
def test_every_clean_corpus_file_scaffolds_to_a_complete_module(style: str, tmp_path: Path) -> None:
    done = 0
    for i, path in enumerate(FILES):
        try:
            rules = RuleSet.from_file(path)
        except UserError:
            continue  # a file with errors has nothing to implement
        out = tmp_path / f"tasks_{i}.py"
        out.write_text(scaffold(rules, rules_path=str(path), style=style), encoding="utf-8")
        module = load(out, f"scaffolded_{style}_{i}")
        m = Manager(rules, clock=VirtualClock())
        module.install(m)  # type: ignore[attr-defined]
        m.start()  # the completeness check: raises BindingError listing what is missing
        m.close()
        done += 1
    assert done >= 140 or not FILES


@pytest.mark.parametrize("style", ["task", "capability"])
@pytest.mark.parametrize("rules", ["examples/assistive_care/rules.sleec", "examples/ros/vacuum/rules.sleec"])
def test_a_scaffold_is_clean_for_ruff_and_mypy_strict(rules: str, style: str, tmp_path: Path) -> None:
    out = tmp_path / "tasks.py"
    out.write_text(scaffold(RuleSet.from_file(ROOT / rules), rules_path=rules, style=style), encoding="utf-8")
    bin_dir = Path(sys.executable).parent
    for cmd in (
        [str(bin_dir / "ruff"), "check", "--config", str(ROOT / "pyproject.toml"), str(out)],
        [str(bin_dir / "ruff"), "format", "--check", "--config", str(ROOT / "pyproject.toml"), str(out)],
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", str(out)],
    ):
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=ROOT)
        assert done.returncode == 0, done.stdout + done.stderr
