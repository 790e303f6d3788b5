"""One error root: every mistake a user can fix is a UserError, which the CLI prints (exit 1)."""

from __future__ import annotations

import pytest

from cosleec.cli.main import main
from cosleec.errors import ConfigurationError, CosleecError, UserError
from cosleec.lang import SleecError, analyse, choose
from cosleec.ros.messages import MessageTypeError, message_class
from cosleec.runtime import BindingError, ContextError, Manager

RULES = "def_start event A event B def_end rule_start R1 when A then B rule_end"


def test_user_errors_share_one_root_and_stay_value_errors_where_they_were() -> None:
    for kind in (SleecError, ContextError, BindingError, ConfigurationError, MessageTypeError):
        assert issubclass(kind, UserError) and issubclass(kind, CosleecError)
    for kind in (ContextError, ConfigurationError, MessageTypeError):
        assert issubclass(kind, ValueError)  # callers that caught ValueError still do


@pytest.mark.parametrize(
    "call",
    [
        lambda: analyse(RULES, dialect="klingon"),
        lambda: choose([True], "first"),  # type: ignore[arg-type]
        lambda: Manager.from_text(RULES, unknown="maybe"),
        lambda: Manager.from_text(RULES, semantics="nestd"),
    ],
)
def test_a_bad_option_names_the_choices(call) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigurationError, match="one of"):
        call()


@pytest.mark.parametrize("name", ["Bool", "std_msgs/Bool/Extra", "no_such_pkg_cosleec/Thing"])
def test_a_bad_message_type_is_a_user_error(name: str) -> None:
    with pytest.raises(MessageTypeError):
        message_class(name)


def test_the_cli_prints_a_user_error_and_exits_1(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    launch = tmp_path / "bad.launch.yaml"
    launch.write_text("backend: ros3\nnodes: []\n")
    assert main(["ros2", "launch", str(launch)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"cosleec: {launch}: expected `backend: ros1|ros2`") and "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["ros2", "launch", "/nonexistent/cosleec.launch.yaml"], "cannot read the launch file"),
        (["demo", "--audit", "/proc/nonexistent/audit.jsonl"], "cannot open the audit log"),
    ],
)
def test_unreadable_and_unwritable_paths_are_user_errors(argv: list[str], message: str, capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert message in err and "internal error" not in err


def test_a_launch_file_that_is_not_yaml_is_a_user_error(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.launch.yaml"
    bad.write_text("backend: [ros2\n")
    assert main(["ros2", "launch", str(bad)]) == 1
    assert "not valid YAML" in capsys.readouterr().err
