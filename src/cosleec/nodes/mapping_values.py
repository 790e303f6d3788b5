"""What a mapping entry may compare a message field with, and what the field holds.

A comparison (``equals: true``, ``below: 10``) that can never match the field it reads is
a mistake that would otherwise show only on the robot, as every message rejected ("... is
False, not comparable with None"). So it is refused when the mapping is read
(:mod:`cosleec.nodes.mapping` adds the file, line and column):

- whatever the message type, a comparison value is one plain value: a boolean, a finite
  number or a text -- never null, a list or a table -- and ``above``, ``below``,
  ``at_least`` and ``at_most`` compare numbers;
- where the type is known, the value is of the field's kind. Known are the ``std_msgs``
  types whose one field ``data`` holds a plain value (:data:`STD_DATA`): cheap to know
  without ROS, and what most mappings read. ``field: percentage`` on ``std_msgs/Float64``
  is refused too (the type has only ``data``).

Each check gives ``(problem, fix)``: the message says what is wrong and why, the hint how
to write it; None when the value fits.
"""

from __future__ import annotations

import math
from typing import Any

from cosleec.errors import show

#: ``std_msgs`` types whose only field, ``data``, holds a plain value: type -> its kind
STD_DATA = {
    "Bool": "boolean",
    "String": "text",
    **{t: "number" for t in ("Float32", "Float64", "Int8", "Int16", "Int32", "Int64")},
    **{t: "number" for t in ("UInt8", "UInt16", "UInt32", "UInt64")},
}
#: comparisons that order numbers (``equals`` and ``not_equals`` compare any plain value)
ORDERING = ("above", "below", "at_least", "at_most")
#: the words YAML 1.1 reads as booleans, which a text field never equals unquoted
YAML_BOOLEANS = "yes, no, on, off, true and false"
#: how an ordering is fixed when the field it reads holds no number, per the field's kind
ORDERING_FIX = {
    "boolean": "compare with `equals: true` or `equals: false`",
    "text": "compare with `equals` or `not_equals`, or read a number (a number type, or `json: true`)",
}
#: how a word YAML read as a boolean is compared with a text field
QUOTE_WORD = "quote the word you wrote: `{op}: 'yes'` is the text yes"
#: how a null comparison is fixed: the every-message event, or a value the field holds
EVERY = (
    "to fire on every message of the topic, leave out the comparison and write "
    "`every_message: true`; otherwise compare with a value the field holds (`not_equals: ''`, "
    "`not_equals: 0`)"
)


def std_type(type_name: str) -> str | None:
    """``Float64`` for ``std_msgs/Float64`` or ``std_msgs/msg/Float64`` when :data:`STD_DATA`
    knows it; None for any other type."""
    package, _, name = type_name.replace("/msg/", "/").partition("/")
    return name if package == "std_msgs" and name in STD_DATA else None


def field_kind(type_name: str, field: tuple[str, ...], json: bool) -> str | None:
    """``boolean``, ``number`` or ``text``: what the field read holds, when the type says it.

    None when it is not known: a type :data:`STD_DATA` does not list, a path into JSON, or
    a field the type has not (:func:`field_problem` refuses that one).
    """
    name = std_type(type_name)
    if name is None or json or field != ("data",):
        return None
    return STD_DATA[name]


def field_problem(type_name: str, field: tuple[str, ...], json: bool) -> tuple[str, str] | None:
    """Why a known ``std_msgs`` type cannot give the field an entry reads (or the JSON text it
    parses), with the fix; None when it can, or the type is not known."""
    name = std_type(type_name)
    if name is None:
        return None
    if json and name != "String":
        return (
            f"`json: true` reads JSON text, but {type_name}'s data is a {STD_DATA[name]}",
            "leave out `json` (or read a std_msgs/String topic whose data is JSON text)",
        )
    if not json and field != ("data",):
        return (
            f"{type_name} has one field, `data`, not {'.'.join(field)!r}",
            "leave out `field` (it reads `data`), or give the type that has this field",
        )
    return None


def value_problem(op: str, value: Any, kind: str | None, type_name: str) -> tuple[str, str] | None:
    """Why comparing with ``value`` by ``op`` can never be right, with the fix; None when it can.

    ``kind`` is the field's (:func:`field_kind`), None when unknown: then only the shape of
    the value is checked. A number's finiteness is checked by the caller (NaN, infinity).
    """
    shape = _shape(op, value)
    if shape is not None or kind is None:
        return shape
    got = _kind_of(value)
    if got == kind:
        return None
    field = f"{type_name}'s data is a {kind}"
    if op in ORDERING:  # the value is a number: the field is not
        return f"`{op}` compares numbers, but {field}", ORDERING_FIX[kind]
    never = f"{field}, so `{op}: {show(value)}` ({got})"
    if kind == "text" and got == "boolean":
        return f"{never} (YAML reads {YAML_BOOLEANS} as booleans) never matches it", QUOTE_WORD.format(op=op)
    fix = {"text": f"quote it: `{op}: '{value}'`", "boolean": f"write `{op}: true` or `{op}: false`"}
    return f"{never} never matches it", fix.get(kind, f"give a number: `{op}: 10`")


def _shape(op: str, value: Any) -> tuple[str, str] | None:
    """What is wrong with ``value`` as any comparison's value (null, a list, a table), or as an
    ordering's (not a number); None when it is one plain value."""
    if value is None:
        return (
            f"`{op}: null` compares with nothing: a message field is never null, so the comparison "
            f"would {'hold for every message' if op == 'not_equals' else 'never hold'}",
            EVERY,
        )
    if not isinstance(value, bool | int | float | str):
        return (
            f"`{op}` compares with one value (a boolean, a number or a text), not {show(value)}",
            f"give one value, such as `{op}: 10` or `{op}: open`",
        )
    if op in ORDERING and _kind_of(value) != "number":
        return f"`{op}` compares numbers, not {show(value)} ({_kind_of(value)})", _number_fix(op, value)
    return None


def _number_fix(op: str, value: Any) -> str:
    """How to write ``value`` as the number ``op`` needs: YAML reads ``1e-3`` (no dot) as text."""
    try:
        number = float(value) if isinstance(value, str) else None
    except ValueError:
        number = None
    if number is not None and math.isfinite(number):
        return f"YAML reads {value} as text: write `{op}: {number!r}`"
    return f"give a number, such as `{op}: 10`"


def _kind_of(value: bool | int | float | str) -> str:
    """``boolean``, ``number`` or ``text``: the kind of a plain comparison value."""
    if isinstance(value, bool):
        return "boolean"
    return "text" if isinstance(value, str) else "number"
