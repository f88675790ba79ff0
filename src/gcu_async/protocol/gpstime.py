"""GNSS week + milliseconds ↔ UTC (Appendix 6; docs/protocol-notes.md, "8. GNSS time and
leap seconds").

The week and milliseconds a GNSS receiver reports count GPS time, which runs 18 s ahead of
UTC since 2017-01-01. Both directions apply the published table below by default
(``apply_leap_seconds=True``), so a UTC time encoded with :func:`utc_to_gps` decodes with
:func:`gps_to_utc` to the same UTC time, and the client, the MAVLink mapping and the
decoders all agree. ``apply_leap_seconds=False`` is the document's Appendix 6 rule (GPS time
taken as UTC, no leap seconds). The table is complete up to the time of writing (no leap
second has been inserted since 2017-01-01).
"""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

from gcu_async._checks import check_bool, check_instance, check_int

GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
SECONDS_PER_WEEK = 604_800
MS_PER_WEEK = SECONDS_PER_WEEK * 1000
UTC_MAX = datetime(9999, 12, 31, 23, 59, tzinfo=timezone.utc)
"""Latest time :func:`utc_to_gps` takes (leap seconds added must stay inside ``datetime``)."""

# UTC date from which GPS − UTC equals the count (IERS Bulletin C).
LEAP_SECONDS: tuple[tuple[datetime, int], ...] = tuple(
    (datetime(y, m, 1, tzinfo=timezone.utc), n)
    for n, (y, m) in enumerate(
        [
            (1981, 7), (1982, 7), (1983, 7), (1985, 7), (1988, 1), (1990, 1), (1991, 1),
            (1992, 7), (1993, 7), (1994, 7), (1996, 1), (1997, 7), (1999, 1), (2006, 1),
            (2009, 1), (2012, 7), (2015, 7), (2017, 1),
        ],
        start=1,
    )
)  # fmt: skip


def gps_minus_utc(utc: datetime) -> int:
    """Leap-second offset GPS − UTC (seconds) in force at ``utc`` (an aware datetime)."""
    _aware("utc", utc)
    offset = 0
    for start, n in LEAP_SECONDS:
        if utc >= start:
            offset = n
    return offset


def gps_to_utc(week: int, ms: int, *, apply_leap_seconds: bool = True) -> datetime:
    """UTC datetime for GNSS ``week`` and milliseconds of week ``ms`` (GPS time: leap seconds
    applied; ``apply_leap_seconds=False`` is the document's rule, GPS time taken as UTC).
    Inverse of :func:`utc_to_gps` with the same ``apply_leap_seconds``; a GPS instant inside
    an inserted leap second (UTC 23:59:60, which ``datetime`` cannot hold) maps to the UTC
    second after it, as the second after it does.
    ``week`` is an ``int`` in the wire's S16 range and ``ms`` in its U32 range (decoded
    frames may carry any of those; ``ms`` past the week's end runs into the next week).
    """
    check_int("week", week, -(2**15), 2**15 - 1)
    check_int("ms", ms, 0, 2**32 - 1, "ms")
    check_bool("apply_leap_seconds", apply_leap_seconds)
    seconds, millis = divmod(ms, 1000)
    gps = GPS_EPOCH + timedelta(days=7 * week, seconds=seconds, microseconds=1000 * millis)
    if not apply_leap_seconds:
        return gps
    utc = gps - timedelta(seconds=gps_minus_utc(gps))
    # near a leap-second boundary the offset of the UTC instant is the right one
    return gps - timedelta(seconds=gps_minus_utc(utc))


def _aware(field: str, utc: object) -> None:
    check_instance(field, utc, datetime, "an aware datetime")
    assert isinstance(utc, datetime)
    if utc.tzinfo is None or utc.utcoffset() is None:
        raise ValueError(f"{field}: {utc!r} is naive; pass an aware datetime (tz=timezone.utc)")


def utc_to_gps(utc: datetime, *, apply_leap_seconds: bool = True) -> tuple[int, int]:
    """(week, milliseconds of week) for an aware ``utc`` datetime: GPS time, leap seconds
    applied (``apply_leap_seconds=False``: the document's rule, UTC taken as GPS time).

    Raises ``TypeError`` for anything but a ``datetime`` (or a non-bool
    ``apply_leap_seconds``), ``ValueError`` for a naive datetime (its time zone would be a
    guess) or a time outside [1980-01-06, 9999-12-31T23:59:00] UTC.
    """
    _aware("gnss_time", utc)
    check_bool("apply_leap_seconds", apply_leap_seconds)
    given = utc
    try:
        utc = utc.astimezone(timezone.utc)
        early, late = utc < GPS_EPOCH, utc > UTC_MAX
    except OverflowError:  # e.g. datetime.min at UTC+1 is before year 1 in UTC
        early = utc.year < 1980
        late = not early
    if early or late:
        side = "before the GPS epoch" if early else "too late for datetime"
        raise ValueError(f"gnss_time: {given.isoformat()} is outside the allowed range "
                         f"[{GPS_EPOCH.isoformat()}, {UTC_MAX.isoformat()}] ({side})")  # fmt: skip
    gps = utc + timedelta(seconds=gps_minus_utc(utc)) if apply_leap_seconds else utc
    total_ms = (gps - GPS_EPOCH) // timedelta(milliseconds=1)
    week, ms = divmod(total_ms, MS_PER_WEEK)
    return int(week), int(ms)
