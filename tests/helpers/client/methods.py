"""GcuClient's command methods, found by what they do rather than by a list: a command
method is one whose body runs a command class (``self._run(TakePhoto(...))``) or what a
builder function makes (``self._build(builder.track, ...)``, ``self._send(...)``)."""

from __future__ import annotations

import inspect
import re

from gcu_async import GcuClient

SENDS = re.compile(r"self\._(?:run|build|send)\(\s*(?:builder\.|c\.)?([A-Za-z_]+)\b")
"""What a method body sends: a command class or a builder function, by name."""


def sent_names() -> dict[str, list[str]]:
    """Every public method of GcuClient that sends a command → what its body names."""
    out = {}
    for name, member in inspect.getmembers(GcuClient, inspect.isfunction):
        if name.startswith("_"):
            continue
        found = SENDS.findall(inspect.getsource(member))
        if found:
            out[name] = found
    return out


def command_methods() -> set[str]:
    return set(sent_names())
