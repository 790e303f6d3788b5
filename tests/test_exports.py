"""The API people type first: ``from cosleec import Manager`` (issue 29, part 5).

The top-level names are exactly those documented in ``cosleec.__all__``, each the same
object as in its own package, and ``import cosleec`` alone loads none of the runtime.
"""

from __future__ import annotations

import subprocess
import sys

import cosleec
import cosleec.errors
import cosleec.runtime

DOCUMENTED = {
    "__version__",
    "Manager",
    "RuleSet",
    "Task",
    "hedge",
    "Decision",
    "Permission",
    "VirtualClock",
    "MonotonicClock",
    "AuditLog",
    "ContextError",
    "BindingError",
    "JournalError",
    "CosleecError",
}


def test_the_exported_names_are_the_documented_ones() -> None:
    assert set(cosleec.__all__) == DOCUMENTED == {*cosleec._EXPORTS, "__version__"}
    assert DOCUMENTED - {"__version__"} <= set(dir(cosleec))


def test_each_export_is_the_object_of_its_package() -> None:
    for name in DOCUMENTED - {"__version__", "CosleecError"}:
        assert getattr(cosleec, name) is getattr(cosleec.runtime, name), name
    assert cosleec.CosleecError is cosleec.errors.CosleecError


def test_a_name_that_is_not_exported_is_an_attribute_error() -> None:
    try:
        cosleec.LayerManager  # noqa: B018 -- an internal: not offered at the top
    except AttributeError as e:
        assert "LayerManager" in str(e)
    else:
        raise AssertionError("cosleec.LayerManager should not be exported")


def test_the_short_form_runs_a_rule_and_import_cosleec_alone_stays_light() -> None:
    code = (
        "import sys, cosleec\n"
        "assert 'cosleec.runtime' not in sys.modules, 'import cosleec loaded the runtime'\n"
        "from cosleec import Manager, VirtualClock\n"
        "m = Manager.from_text('def_start event E event F def_end rule_start R1 when E then F rule_end',"
        " clock=VirtualClock())\n"
        "m.start(check=False)\n"
        "print(m.event('E')[0].rule)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "R1"
