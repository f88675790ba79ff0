"""The session's options are one checked object (``SessionConfig``): every option checked
when it is made, the error naming the field, its range and the value; ``Session(config)``
and ``Session(**options)`` are the same session."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, get_type_hints

import pytest

from gcu_async.errors import FieldRangeError
from gcu_async.session import Session, SessionConfig
from gcu_async.session.config import OPTIONS, SessionOptions

BAD: dict[str, list[tuple[Any, type[Exception], str]]] = {
    "rate_hz": [(1.9, FieldRangeError, "[2, 200] Hz"), (True, TypeError, "real number")],
    "reorder_guard": [(-0.001, FieldRangeError, "s"), ("0", TypeError, "real number")],
    "command_timeout": [(0, FieldRangeError, "greater than 0"), (math.inf, FieldRangeError, "")],
    "queue_timeout": [(-1, FieldRangeError, ""), (None, TypeError, "real number")],
    "silence_timeout": [(0.02, FieldRangeError, "heartbeat period")],
    "control_silence": [(0.0, FieldRangeError, "greater than 0")],
    "reply_window": [(math.nan, FieldRangeError, "")],
    "record_settle": [(-5, FieldRangeError, "")],
    "aircraft_timeout": [(0.0, FieldRangeError, "greater than 0"), (10.5, FieldRangeError, "")],
    "version": [(3, FieldRangeError, "[1, 2]"), (2.0, TypeError, "integer")],
    "name": [(b"gcu", TypeError, "str")],
}  # fmt: skip


def test_every_option_has_its_bad_values() -> None:
    assert set(BAD) == set(OPTIONS)


@pytest.mark.parametrize(("field", "value", "error", "words"),
                         [(f, *case) for f, cases in BAD.items() for case in cases])  # fmt: skip
def test_a_bad_option_names_its_field_range_and_value(field: str, value: Any,
                                                      error: type[Exception],
                                                      words: str) -> None:  # fmt: skip
    with pytest.raises(error) as made:
        SessionConfig(**{field: value})
    message = str(made.value)
    assert message.startswith(f"{field}: ") and repr(value) in message and words in message
    with pytest.raises(error) as direct:
        Session(**{field: value})  # type: ignore[misc]
    assert str(direct.value) == message


def test_the_first_bad_option_in_field_order_is_the_error() -> None:
    with pytest.raises(FieldRangeError, match=r"^rate_hz: "):
        SessionConfig(version=9, rate_hz=500.0)


def test_checked_values_are_kept_as_floats_and_the_config_is_frozen() -> None:
    config = SessionConfig(rate_hz=30, command_timeout=1, silence_timeout=2)
    assert (config.rate_hz, config.command_timeout, config.silence_timeout) == (30.0, 1.0, 2.0)
    assert type(config.rate_hz) is float and type(config.command_timeout) is float
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.rate_hz = 40.0  # type: ignore[misc]


def test_session_takes_a_config_or_its_fields() -> None:
    config = SessionConfig(rate_hz=40.0, reorder_guard=0.015, name="pod")
    assert Session(config).config is config
    assert Session(rate_hz=40.0, reorder_guard=0.015, name="pod").config == config
    assert Session().config == SessionConfig()
    with pytest.raises(TypeError, match="not both"):
        Session(config, rate_hz=40.0)
    with pytest.raises(TypeError, match=r"^config: expected a SessionConfig"):
        Session({"rate_hz": 40.0})  # type: ignore[arg-type]


def test_the_keyword_options_are_the_config_fields() -> None:
    """``SessionOptions`` (what ``Session(**options)`` is typed with) lists exactly the
    config's fields, with their types."""
    hints = get_type_hints(SessionOptions)
    fields = {f.name: f.type for f in dataclasses.fields(SessionConfig)}
    assert list(hints) == list(fields) == list(OPTIONS)
    assert {k: v.__name__ for k, v in hints.items()} == fields
