"""Typed ROS messages <-> dicts, for the Context Listener (std_msgs and nested messages)."""

from __future__ import annotations

import importlib
from typing import Any


def message_class(type_name: str) -> Any:
    """``std_msgs/Bool`` (or ``std_msgs/msg/Bool``) -> the message class.

    ValueError for a malformed name or a type the package lacks; ImportError when the
    message package is not installed.
    """
    parts = type_name.replace("/msg/", "/").split("/")
    if len(parts) != 2 or not all(p.isidentifier() for p in parts):
        raise ValueError(f"message type {type_name!r} is not of the form package/Type")
    module = importlib.import_module(f"{parts[0]}.msg")
    try:
        return getattr(module, parts[1])
    except AttributeError:
        raise ValueError(f"no message type {type_name!r}") from None


def to_dict(msg: Any) -> Any:
    """A message as nested dicts (fields of both ROS 2 and ROS 1 messages)."""
    fields = getattr(msg, "get_fields_and_field_types", None)
    names = list(fields()) if fields is not None else list(getattr(msg, "__slots__", ()))
    if not names:
        return msg
    out = {}
    for n in names:
        v = getattr(msg, n.lstrip("_"), None) if fields is not None else getattr(msg, n)
        out[n.lstrip("_")] = to_dict(v) if hasattr(v, "__slots__") and not isinstance(v, str | bytes) else v
    return out
