"""The argument parser every ``gcu-async`` parser derives from: a value that is a negative
number, or a comma-separated list of numbers starting with one, is a value, never an option.
And :func:`in_option_terms`: a library's error about a parameter, told as the option's.

argparse takes ``-33.85,151.2,50`` (``send … --aircraft``) or ``-1e-3`` for an option: its
test for "a negative number" knows only ``-12`` and ``-1.5``. Southern and western
coordinates start with a minus, so the test is widened here, once for every sub-command.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Mapping
from typing import Any

_NUMBER = r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
NEGATIVE_VALUE = re.compile(rf"^-{_NUMBER}(?:,[-+]?{_NUMBER})*$")
"""A negative number (exponent allowed) or a comma-separated list of numbers whose first
is negative: what argparse must read as a value, not as an option."""


class CliParser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` reading :data:`NEGATIVE_VALUE` as values (with or without
    ``--option=``). No ``gcu-async`` option looks like a number, so nothing is lost."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # argparse's own test, consulted by _parse_optional (3.10-3.13 spell it so)
        self._negative_number_matcher = NEGATIVE_VALUE


def in_option_terms(exc: ValueError, options: Mapping[str, str]) -> str:
    """The message of ``exc``, a library's ``ValueError`` that names its parameter first
    (``system_id: 300 is outside …``), naming instead the command-line option that gave the
    value (``--system-id: 300 is outside …``); ``options`` maps parameter to option. Any
    other message is returned as it is."""
    text = str(exc)
    for name, option in options.items():
        if text.startswith(f"{name}: "):
            return option + text[len(name) :]
    return text
