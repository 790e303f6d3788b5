"""The one conftest: COP isolation for every test, the corpus location, Hypothesis settings.

- COP: the public ``cosleec.testing.plugin`` gives each test a clean global COP
  configuration and restores it afterwards.
- Corpus: ``../shared/sleec-corpus`` (or ``$COSLEEC_CORPUS``); under CI (``$CI`` set) a
  missing corpus fails the run instead of skipping the corpus tests.
- Hypothesis keeps its example database outside the work tree.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir
from hypothesis.database import DirectoryBasedExampleDatabase

from cosleec.testing import corpus_dir, corpus_files

pytest_plugins = ["cosleec.testing.plugin"]

ROOT = Path(__file__).resolve().parent.parent
CORPUS = corpus_dir()

HYPOTHESIS_HOME = Path(tempfile.gettempdir()) / "cosleec-hypothesis"
set_hypothesis_home_dir(str(HYPOTHESIS_HOME))  # everything Hypothesis stores, out of the work tree
settings.register_profile("cosleec", database=DirectoryBasedExampleDatabase(HYPOTHESIS_HOME / "examples"))
settings.load_profile("cosleec")


@pytest.fixture
def corpus() -> list[Path]:
    """The corpus files, or a skip when the corpus is absent (never under CI: there it fails)."""
    files = corpus_files()
    if not files:
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    return files


# -- the express lane and the general path (scripts/test) --------------------------------
# With COSLEEC_PATHS_OUT=DIR, each worker writes to DIR the node ids of the tests whose run the
# express lane could have changed: it took a trigger or an update in this process or in a Python process
# the test started (tests/tools/witness/sitecustomize.py tells), or the test started a
# Python process without that witness (its own environment). Every other test ran the
# general path's code alone (with the lane off, a Manager differs only in never asking it),
# so running these again with COSLEEC_EXPRESS=0 runs the whole suite against the general path.
_PATHS_OUT = os.environ.get("COSLEEC_PATHS_OUT")
_WITNESS_DIR = ROOT / "tests" / "tools" / "witness"
_witnessed = [False]


def _python_child(args: object) -> bool:
    """Does this command start Python (a child that may build a Manager)?"""
    first = args if isinstance(args, str | bytes | os.PathLike) else next(iter(args), "")  # type: ignore[call-overload]
    words = os.fsdecode(first).split()
    name = Path(words[0]).name if words else ""
    return "python" in name or name == "cosleec"


if _PATHS_OUT:
    from cosleec.runtime.express import Express
    from cosleec.runtime.plans import Plans

    _taking = Express._put_in_force
    _planning = Plans.trigger_function
    _updating = Express.update
    _spawning = subprocess.Popen.__init__

    def _taken(self: Express, *args: Any) -> Any:
        _witnessed[0] = True
        return _taking(self, *args)

    def _planned(self: Plans) -> Any:
        trigger = _planning(self)

        def noted(name: str) -> Any:
            out = trigger(name)
            if out is not None:  # a plan took the trigger
                _witnessed[0] = True
            return out

        return noted

    def _updated(self: Express, *args: Any) -> Any:
        out = _updating(self, *args)
        if out is not None:  # the lane took the update
            _witnessed[0] = True
        return out

    def _spawned(self: subprocess.Popen[Any], args: Any, *rest: Any, **kw: Any) -> None:
        env = kw.get("env")
        env = os.environ if env is None else env
        if _python_child(args) and not str(env.get("PYTHONPATH", "")).startswith(str(_WITNESS_DIR)):
            _witnessed[0] = True  # a child without the witness: it may have taken the lane
        _spawning(self, args, *rest, **kw)

    Express._put_in_force = _taken  # type: ignore[method-assign]
    Plans.trigger_function = _planned  # type: ignore[method-assign]
    Express.update = _updated  # type: ignore[method-assign]
    subprocess.Popen.__init__ = _spawned  # type: ignore[method-assign]

    @pytest.fixture(autouse=True)
    def _express_witness(
        request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
    ) -> Iterator[None]:
        """Note the test when the express lane ran in it (here or in a child)."""
        witness = tmp_path_factory.mktemp("witness") / "taken"
        outer = {k: os.environ.get(k) for k in ("COSLEEC_PATHS_WITNESS", "PYTHONPATH")}
        os.environ["COSLEEC_PATHS_WITNESS"] = str(witness)
        os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(_WITNESS_DIR), outer["PYTHONPATH"]) if p)
        _witnessed[0] = False
        try:
            yield
        finally:
            for k, v in outer.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        if _witnessed[0] or witness.exists():
            worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
            with open(Path(_PATHS_OUT) / f"{worker}.txt", "a", encoding="utf-8") as out:
                out.write(request.node.nodeid + "\n")
