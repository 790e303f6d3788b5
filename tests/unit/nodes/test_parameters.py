"""Node options as ROS parameters: the type checks of ``coerce``, unknown parameters
(``check_overrides``), and how ``split_ros_args`` takes the ROS arguments
out of a command line -- all without a middleware."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.cli.ros import split_ros_args
from cosleec.errors import UserError
from cosleec.ros.parameters import ParameterError, check_overrides, coerce

# ----------------------------------------------------------------------------- coerce


@pytest.mark.parametrize(
    ("value", "default", "expected"),
    [
        # None default: a string, "" or None meaning "not given"
        ("rules.sleec", None, "rules.sleec"),
        ("", None, None),
        (None, None, None),
        # bool
        (True, False, True),
        (False, True, False),
        # float: a float, or an int (as a float)
        (2.5, 0.5, 2.5),
        (3, 0.5, 3.0),
        (0, 0.5, 0.0),
        (-1, 2.0, -1.0),
        # int
        (7, 1, 7),
        (0, 5, 0),
        (-3, 0, -3),
        # list of strings: a list, a tuple, one string
        (["a", "b"], [], ["a", "b"]),
        (("a", "b"), ["x"], ["a", "b"]),
        ([], ["x"], []),
        ("a", [], ["a"]),
        ("", ["x"], []),
        # str
        ("nested", "last-wins", "nested"),
        ("", "last-wins", ""),
    ],
)
def test_coerce_accepts(value: Any, default: Any, expected: Any) -> None:
    got = coerce("p", value, default)
    assert got == expected
    assert type(got) is type(expected)


@pytest.mark.parametrize(
    ("value", "default", "says"),
    [
        # None default
        (5, None, "must be a string"),
        (True, None, "must be a string"),
        (0, None, "must be a string"),
        (False, None, "must be a string"),
        (["a"], None, "must be a string"),
        # bool: never an int, never a string
        (1, False, "must be true or false"),
        (0, True, "must be true or false"),
        ("true", False, "must be true or false"),
        (None, False, "must be true or false"),
        # float: a bool is not a number here
        (True, 0.5, "must be a number"),
        (False, 0.5, "must be a number"),
        ("1.5", 0.5, "must be a number"),
        (None, 0.5, "must be a number"),
        # int: a bool is not a whole number, nor is a float (even a round one)
        (True, 1, "must be a whole number"),
        (False, 0, "must be a whole number"),
        (2.0, 1, "must be a whole number"),
        (2.5, 1, "must be a whole number"),
        ("3", 1, "must be a whole number"),
        # list
        ([1, 2], [], "must be a list of strings"),
        (["a", 1], [], "must be a list of strings"),
        (5, [], "must be a list of strings"),
        (None, [], "must be a list of strings"),
        ({"a": "b"}, [], "must be a list of strings"),
        # str
        (5, "last-wins", "must be a string"),
        # (a boolean for a string option is its word: test_a_boolean_for_a_string_option_is_its_word)
        (None, "last-wins", "must be a string"),
        (["nested"], "last-wins", "must be a string"),
    ],
)
def test_coerce_refuses(value: Any, default: Any, says: str) -> None:
    with pytest.raises(ParameterError) as info:
        coerce("semantics", value, default)
    assert info.value.message == f"parameter 'semantics' {says}, not {value!r}"
    assert isinstance(info.value, UserError)


def test_coerce_returns_a_new_list_not_the_given_one() -> None:
    given_list = ["a"]
    got = coerce("p", given_list, [])
    assert got == ["a"] and got is not given_list  # the caller's list is not aliased
    assert isinstance(coerce("p", ("a",), []), list)


@given(st.integers(-(2**62), 2**62))
def test_coerce_any_int_for_a_float_option_is_that_number(n: int) -> None:
    got = coerce("timeout", n, 0.5)
    assert isinstance(got, float) and got == float(n)


@given(st.booleans(), st.sampled_from([0, 1, 0.0, 2.5]))
def test_coerce_a_bool_never_passes_as_a_number(b: bool, default: Any) -> None:
    with pytest.raises(ParameterError):
        coerce("n", b, default)


# ----------------------------------------------------------------------------- check_overrides


KNOWN = {"rules", "semantics", "status_each", "sim_time", "namespace"}


def test_check_overrides_accepts_known_and_none() -> None:
    check_overrides([], KNOWN)
    check_overrides(["rules", "semantics"], KNOWN)
    check_overrides(iter(["namespace"]), KNOWN)  # any iterable


def test_check_overrides_unknown_with_did_you_mean() -> None:
    with pytest.raises(ParameterError) as info:
        check_overrides(["rules", "semantcs"], KNOWN)
    assert info.value.message == "no parameter 'semantcs' on this node"
    assert info.value.hint == "did you mean 'semantics'?"
    assert isinstance(info.value, UserError)


def test_check_overrides_unknown_without_a_close_match_lists_the_parameters() -> None:
    with pytest.raises(ParameterError) as info:
        check_overrides(["xyzzy"], KNOWN)
    assert info.value.message == "no parameter 'xyzzy' on this node"
    assert info.value.hint == "parameters: namespace, rules, semantics, sim_time, status_each"


def test_check_overrides_names_the_first_unknown_in_sorted_order() -> None:
    with pytest.raises(ParameterError, match="no parameter 'aaa'"):
        check_overrides(["zzz", "rules", "aaa"], KNOWN)


@pytest.mark.parametrize(
    "name",
    [
        "qos_overrides./cmd_vel.publisher.depth",
        "qos_overrides./cosleec/events.subscription.reliability",
        "qos_overrides.",
    ],
)
def test_check_overrides_ignores_qos_overrides(name: str) -> None:
    check_overrides([name], KNOWN)
    check_overrides([name, "rules"], KNOWN)
    with pytest.raises(ParameterError, match="'semantcs'"):  # and goes on checking the others
        check_overrides([name, "semantcs"], KNOWN)


@pytest.mark.parametrize("name", ["qos_overrides", "qos_override.x", "xqos_overrides.a"])
def test_check_overrides_only_the_qos_overrides_prefix_is_ignored(name: str) -> None:
    with pytest.raises(ParameterError):
        check_overrides([name], KNOWN)


# ----------------------------------------------------------------------------- split_ros_args


@pytest.mark.parametrize(
    ("argv", "rest", "ros"),
    [
        ([], [], []),
        (["manager", "rules.sleec"], ["manager", "rules.sleec"], []),
        # ROS 2: at the end, to the end
        (
            ["manager", "rules.sleec", "--ros-args", "-p", "semantics:=nested"],
            ["manager", "rules.sleec"],
            ["--ros-args", "-p", "semantics:=nested"],
        ),
        # ROS 2: in the middle, up to a lone `--` (which is neither's)
        (
            [
                "manager",
                "--ros-args",
                "-p",
                "semantics:=nested",
                "-r",
                "__node:=m",
                "--",
                "rules.sleec",
                "--sim-time",
            ],
            ["manager", "rules.sleec", "--sim-time"],
            ["--ros-args", "-p", "semantics:=nested", "-r", "__node:=m"],
        ),
        # the lone `--` right after --ros-args: an empty block
        (["a", "--ros-args", "--", "b"], ["a", "b"], ["--ros-args"]),
        # --ros-args last: just itself
        (["a", "--ros-args"], ["a"], ["--ros-args"]),
        # two blocks
        (
            ["--ros-args", "-p", "a:=1", "--", "x", "--ros-args", "-p", "b:=2"],
            ["x"],
            ["--ros-args", "-p", "a:=1", "--ros-args", "-p", "b:=2"],
        ),
        # a params file inside the block, paths with `--` in them
        (
            ["guard", "--ros-args", "--params-file", "/tmp/p--x.yaml", "--", "--timeout", "1"],
            ["guard", "--timeout", "1"],
            ["--ros-args", "--params-file", "/tmp/p--x.yaml"],
        ),
        # a second lone `--` after the block stays in the rest (argparse's end of options)
        (
            ["a", "--ros-args", "-p", "x:=1", "--", "--", "-b"],
            ["a", "--", "-b"],
            ["--ros-args", "-p", "x:=1"],
        ),
        # ROS 1: remappings and private parameters, anywhere
        (
            ["_semantics:=nested", "manager", "rules.sleec", "__name:=m", "/chatter:=/talk"],
            ["manager", "rules.sleec"],
            ["_semantics:=nested", "__name:=m", "/chatter:=/talk"],
        ),
        (["manager", "_x:=y", "rules.sleec"], ["manager", "rules.sleec"], ["_x:=y"]),
        # an option that starts with `-` is the program's, `:=` or not
        (
            ["manager", "--rules=a:=b.sleec", "-x:=1", "rules.sleec"],
            ["manager", "--rules=a:=b.sleec", "-x:=1", "rules.sleec"],
            [],
        ),
        # both kinds at once
        (
            ["_a:=1", "task", "--ros-args", "-p", "name:=t", "--", "--module", "m", "b:=2"],
            ["task", "--module", "m"],
            ["_a:=1", "--ros-args", "-p", "name:=t", "b:=2"],
        ),
    ],
)
def test_split_ros_args(argv: list[str], rest: list[str], ros: list[str]) -> None:
    before = list(argv)
    assert split_ros_args(argv) == (rest, ros)
    assert argv == before  # the caller's list is left alone


TOKEN = st.sampled_from(["a", "-b", "--c", "x:=1", "_p:=2", "-q:=3", "--ros-args", "--", "-p", "r"])


@given(st.lists(TOKEN, max_size=12))
def test_split_ros_args_loses_nothing_but_block_ends(argv: list[str]) -> None:
    rest, ros = split_ros_args(argv)
    # every token lands on one side, in order, except the `--` that ends a --ros-args block
    assert len(rest) + len(ros) <= len(argv)
    dropped = len(argv) - len(rest) - len(ros)
    assert dropped <= argv.count("--")
    assert all(":=" not in a or a.startswith("-") for a in rest)
    it = iter(argv)
    assert all(any(a == b for b in it) for a in rest)  # rest is a subsequence of argv
    if "--ros-args" not in argv:
        assert dropped == 0


def test_importing_the_ros_cli_needs_neither_rclpy_nor_rospy() -> None:
    code = (
        "import sys\n"
        "for m in ('rclpy', 'rospy', 'rosgraph', 'std_msgs', 'cosleec_interfaces'):\n"
        "    sys.modules[m] = None  # importing it raises ImportError\n"
        "import cosleec.cli.ros as r\n"
        "from cosleec.cli.main import main\n"
        "assert r.split_ros_args(['a', '_x:=1']) == (['a'], ['_x:=1'])\n"
        "import cosleec.ros.parameters, cosleec.ros.diagnostics\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


@pytest.mark.parametrize(("value", "word"), [(False, "false"), (True, "true")])
def test_a_boolean_for_a_string_option_is_its_word(value: bool, word: str) -> None:
    # ROS reads `-p unknown:=false` as a boolean; --unknown's choices include "false"
    assert coerce("unknown", value, "undetermined") == word
