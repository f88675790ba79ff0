"""Strict argument checks shared by every public entry point (not public API).

The rule (docs/client.md, "The API boundary"): a ``bool`` is a ``bool`` (no truthiness), an
integer is an ``int`` (not a bool, not a float), a real number is a finite ``int`` or
``float`` (not a bool), an enum takes its members or their exact integer values. Nothing is
coerced, clipped or wrapped. A wrong type raises ``TypeError``, a value out of range
:class:`~gcu_async.errors.FieldRangeError` (a ``ValueError``); both name the field, what is
allowed and the value given.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable
from enum import Enum
from typing import TypeVar

from gcu_async.errors import FieldRangeError

E = TypeVar("E", bound=Enum)
T = TypeVar("T")


def did_you_mean(given: str, names: Iterable[str], n: int = 1) -> str:
    """The one wording of a suggestion for a misspelt name: ``"did you mean 'zoom-to'?"``
    (up to ``n`` of the closest ``names``, joined by "or"), or ``""`` if none is close."""
    close = difflib.get_close_matches(given, list(names), n=n)
    return f"did you mean {' or '.join(map(repr, close))}?" if close else ""


def type_error(field: str, expected: str, value: object) -> TypeError:
    """The one wording of a type error: field, what is expected, what was given."""
    return TypeError(f"{field}: expected {expected}, got {type(value).__name__} {value!r}")


def check_bool(field: str, value: object) -> bool:
    """``value`` if it is ``True`` or ``False``; anything else (0, 1, "false", None) is a
    ``TypeError``."""
    if value is True or value is False:
        return value
    raise type_error(field, "a bool (True or False)", value)


def check_int(field: str, value: object, low: int | None = None, high: int | None = None,
              unit: str = "") -> int:  # fmt: skip
    """``value`` as an ``int`` in ``[low, high]`` (either bound optional). Bools and floats
    (even 1.0) are rejected."""
    if type(value) is not int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise type_error(field, "an integer", value)
        value = int(value)  # an IntEnum/IntFlag member: its exact value
    if (low is not None and value < low) or (high is not None and value > high):
        raise FieldRangeError(
            field, value, low if low is not None else -math.inf,
            high if high is not None else math.inf, unit,
        )  # fmt: skip
    return value


def check_real(
    field: str,
    value: object,
    low: float = -math.inf,
    high: float = math.inf,
    unit: str = "",
    *,
    high_open: bool = False,
    detail: str = "",
) -> float:
    """``value`` as a finite ``float`` in ``[low, high]`` (``[low, high)`` with
    ``high_open``). Accepts ``int`` and ``float`` (and their subclasses, e.g. numpy's
    float64); rejects bools, strings, None, NaN and infinities."""
    if type(value) is not float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise type_error(field, "a real number", value)
        try:
            value = float(value)
        except OverflowError:  # an int too large for a float
            raise FieldRangeError(field, value, low, high, unit, high_open=high_open,
                                  detail=detail or "not representable") from None  # fmt: skip
    if not math.isfinite(value) or not (low <= value < high if high_open else low <= value <= high):
        extra = detail or ("not a finite number" if not math.isfinite(value) else "")
        raise FieldRangeError(field, value, low, high, unit, high_open=high_open, detail=extra)
    return value


def check_positive(field: str, value: object, *, allow_zero: bool = False,
                   unit: str = "s") -> float:  # fmt: skip
    """A finite real number > 0 (``>= 0`` with ``allow_zero``), e.g. a duration."""
    f = check_real(field, value, 0.0, math.inf, unit, high_open=True)
    if f == 0.0 and not allow_zero:
        raise FieldRangeError(field, value, 0.0, math.inf, unit, high_open=True,
                              detail="must be greater than 0")  # fmt: skip
    return f


def check_enum(field: str, value: object, enum: type[E]) -> E:
    """A member of ``enum``, or the exact value of one (an ``int`` for int enums; never a
    bool or a float)."""
    if isinstance(value, enum):
        return value
    if isinstance(value, (bool, float)) or (issubclass(enum, int) and not isinstance(value, int)):
        raise type_error(field, f"a {enum.__name__} member or its integer value", value)
    try:
        member = enum(value)
    except (ValueError, TypeError):
        allowed = ", ".join(f"{m.name}={m.value!r}" for m in enum)
        raise ValueError(
            f"{field}: {value!r} is not a {enum.__name__} (allowed: {allowed})"
        ) from None
    if member.name == "UNKNOWN":  # enums that map unknown values to UNKNOWN on decode
        allowed = ", ".join(f"{m.name}={m.value!r}" for m in enum if m.name != "UNKNOWN")
        raise ValueError(f"{field}: {value!r} is not a {enum.__name__} (allowed: {allowed})")
    return member


def check_instance(field: str, value: object, cls: type[T], expected: str = "") -> T:
    """``value`` if it is an instance of ``cls``, else a ``TypeError``."""
    if not isinstance(value, cls):
        raise type_error(field, expected or f"a {cls.__name__}", value)
    return value
