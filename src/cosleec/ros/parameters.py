"""Node options as ROS parameters: ``--ros-args -p semantics:=nested`` and ``--params-file``.

ROS developers configure nodes with parameters, not only with command-line options. Every
option of a cosleec node is also a parameter of the same name (``-`` as ``_``); a
parameter given wins over the option's default. A parameter no option has is an error
with a did-you-mean -- silently ignoring ``-p semantcs:=nested`` would run the robot
under rules its operator did not choose. The middleware-specific part (declaring and
reading) is the transports'; the checks are here.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any

from cosleec.errors import UserError


class ParameterError(UserError):
    """A ROS parameter is unknown or has a value its option does not take."""


def coerce(name: str, value: Any, default: Any) -> Any:
    """``value`` as the type of ``default`` (an integer given for a float option is fine).

    ``""`` for an option whose default is None means "not given" (ROS parameters have no
    null); a list option takes a list of strings. ParameterError otherwise.
    """
    if default is None:
        if value in ("", None):
            return None
        if not isinstance(value, str):
            raise ParameterError(f"parameter {name!r} must be a string, not {value!r}")
        return value
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ParameterError(f"parameter {name!r} must be true or false, not {value!r}")
        return value
    if isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ParameterError(f"parameter {name!r} must be a number, not {value!r}")
        return float(value)
    if isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(f"parameter {name!r} must be a whole number, not {value!r}")
        return value
    if isinstance(default, list):
        if isinstance(value, str):
            return [value] if value else []
        if not isinstance(value, list | tuple) or not all(isinstance(v, str) for v in value):
            raise ParameterError(f"parameter {name!r} must be a list of strings, not {value!r}")
        return list(value)
    if isinstance(value, bool):  # YAML reads `unknown:=false` as a boolean: the option's word
        return "true" if value else "false"
    if not isinstance(value, str):
        raise ParameterError(f"parameter {name!r} must be a string, not {value!r}")
    return value


def check_overrides(given: Iterable[str], known: set[str]) -> None:
    """ParameterError naming the first parameter in ``given`` that no option has (with did-you-mean)."""
    for name in sorted(set(given) - known):
        if name.startswith("qos_overrides."):
            continue
        close = difflib.get_close_matches(name, sorted(known), n=1)
        raise ParameterError(
            f"no parameter {name!r} on this node",
            hint=f"did you mean {close[0]!r}?" if close else f"parameters: {', '.join(sorted(known))}",
        )
