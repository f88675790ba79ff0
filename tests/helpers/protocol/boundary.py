"""What the two boundary tables (tests/protocol/test_protocol_boundary.py, the protocol's
constructors; tests/client/test_client_boundary.py, the client's methods) share: how a range
error's message reads, and how a case is named."""

from __future__ import annotations

import re
from typing import Any

MESSAGE = re.compile(
    r"^(?P<field>.+?): (?P<value>.+?) is outside the allowed range "
    r"\[(?P<low>[^,]+), (?P<high>[^\]\)]+)(?P<close>[\]\)])"
)
"""A :class:`~gcu_async.errors.FieldRangeError` message: field, value, range and its end."""

_ADDRESS = re.compile(r" at 0x[0-9a-f]+")
"""Memory addresses in reprs: left out of test ids, which must be the same in every process
(pytest-xdist's workers collect separately and compare)."""


def case_id(owner: str, param: str, value: Any) -> str:
    """``owner.param=value`` (a function or class by its name), at most 40 characters of
    value, the same in every process."""
    text = repr(value) if not callable(value) or isinstance(value, type) else getattr(
        value, "__name__", "fn")
    return f"{owner}.{param}={_ADDRESS.sub('', text)[:40]}"
