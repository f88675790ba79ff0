"""GcuClient's command methods, found by what they do rather than by a list: a command
method is one whose body builds a catalogue entry (``self._run("name", ...)`` or
``self._send("name", ...)``)."""

from __future__ import annotations

import inspect
import re

from gcu_async import GcuClient

BUILDS = re.compile(r"self\._(?:run|send)\(\s*\"([a-z_]+)\"")


def built_entries() -> dict[str, list[str]]:
    """Every public method of GcuClient that builds an entry → the entries it builds."""
    out = {}
    for name, member in inspect.getmembers(GcuClient, inspect.isfunction):
        if name.startswith("_"):
            continue
        found = BUILDS.findall(inspect.getsource(member))
        if found:
            out[name] = found
    return out


def command_methods() -> set[str]:
    return set(built_entries())
