"""Typed ROS messages <-> dicts, for the Context Listener (std_msgs and nested messages)."""

from __future__ import annotations

import importlib
from typing import Any

from cosleec.errors import UserError


class MessageTypeError(UserError, ValueError):
    """A mapping names a ROS message type that is malformed, unknown or not installed here."""


def message_class(type_name: str) -> Any:
    """``std_msgs/Bool`` (or ``std_msgs/msg/Bool``) -> the message class.

    :class:`MessageTypeError` for a malformed name, a package that is not installed, or a
    type the package lacks.
    """
    parts = type_name.replace("/msg/", "/").split("/")
    if len(parts) != 2 or not all(p.isidentifier() for p in parts):
        raise MessageTypeError(f"message type {type_name!r} is not of the form package/Type")
    try:
        module = importlib.import_module(f"{parts[0]}.msg")
    except ImportError:
        raise MessageTypeError(
            f"message package {parts[0]!r} is not installed here (type {type_name!r})",
            hint="install its ROS package in this environment, or map a type it has",
        ) from None
    try:
        return getattr(module, parts[1])
    except AttributeError:
        raise MessageTypeError(f"no message type {type_name!r} in package {parts[0]!r}") from None


def to_dict(msg: Any) -> Any:
    """A message as nested dicts, arrays of messages as lists of dicts (ROS 2 and ROS 1 messages)."""
    fields = getattr(msg, "get_fields_and_field_types", None)
    names = list(fields()) if fields is not None else list(getattr(msg, "__slots__", ()))
    if not names:
        return msg
    out: dict[str, Any] = {}
    for n in names:
        v = getattr(msg, n.lstrip("_"), None) if fields is not None else getattr(msg, n)
        if isinstance(v, list | tuple) and v and _is_message(v[0]):  # an array of messages
            out[n.lstrip("_")] = [to_dict(x) for x in v]
        else:
            out[n.lstrip("_")] = to_dict(v) if _is_message(v) else v
    return out


def _is_message(v: Any) -> bool:
    return hasattr(v, "__slots__") and not isinstance(v, str | bytes)
