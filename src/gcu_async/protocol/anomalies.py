"""Anomalies: values of a CRC-valid packet that V2.0.6 does not expect, kept and flagged.

Receive is liberal, send is strict (docs/client.md, "Liberal receive, strict send"): a
packet whose header, length and CRC are right always decodes; each value outside what the
document defines (a version other than 1 or 2, an execution status a command does not
answer, status bytes beyond the one it defines, a command parameter outside its range or
of the wrong length, a frame field outside its documented range or with reserved bits set)
becomes one :class:`Anomaly` on the decoded object. An anomaly holds exactly what a
:class:`~gcu_async.errors.FieldRangeError` holds — the strict side raises that error for
the same value (:meth:`Anomaly.error`).
"""

from __future__ import annotations

from typing import NamedTuple, TypedDict

from gcu_async.errors import FieldRangeError


class Anomaly(NamedTuple):
    """One unexpected value of a decoded packet: ``field`` holds the raw ``value`` (as on
    the wire), allowed is ``low`` … ``high`` (raw units, ``unit``), ``detail`` says more
    (which values inside the range are meant, or the rule it breaks)."""

    field: str
    value: int
    low: int
    high: int
    unit: str = ""
    detail: str = ""

    def error(self) -> FieldRangeError:
        """The :class:`FieldRangeError` the send side raises for this value."""
        return FieldRangeError(self.field, self.value, self.low, self.high, self.unit,
                               detail=self.detail)  # fmt: skip

    def __str__(self) -> str:
        return str(self.error())

    def as_dict(self) -> AnomalyDict:
        """The anomaly for JSON output, its message included."""
        return {"field": self.field, "value": self.value, "low": self.low, "high": self.high,
                "unit": self.unit, "detail": self.detail, "message": str(self)}  # fmt: skip


class AnomalyDict(TypedDict):
    """What :meth:`Anomaly.as_dict` returns."""

    field: str
    value: int
    low: int
    high: int
    unit: str
    detail: str
    message: str
    """``str(anomaly)``: the words of the send side's :class:`FieldRangeError`."""


def check_raw(field: str, value: int, low: int, high: int, unit: str = "",
              detail: str = "") -> tuple[Anomaly, ...]:  # fmt: skip
    """``()`` if ``low <= value <= high``, else the one anomaly."""
    if low <= value <= high:
        return ()
    return (Anomaly(field, value, low, high, unit, detail),)


VERSION_DETAIL = "V2.0.6 defines versions 1 and 2; decoded with its layout"


def reserved_bits_detail(reserved: int) -> str:
    """The detail of a flags value with ``reserved`` bits set, on both sides."""
    return f"reserved bits 0x{reserved:X} must be zero"
