"""GNSS week + ms ↔ UTC (Appendix 6): the document's rule (no leap seconds) and the
leap-second option."""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import HostSubFrame, gps_to_utc, utc_to_gps
from gcu_async.protocol.gpstime import GPS_EPOCH, LEAP_SECONDS, gps_minus_utc

UTC = timezone.utc
EXAMPLE_UTC = datetime(2023, 9, 7, 1, 58, 38, tzinfo=UTC)


def test_document_example_without_leap_seconds() -> None:
    assert gps_to_utc(2278, 352718000) == EXAMPLE_UTC
    assert utc_to_gps(EXAMPLE_UTC) == (2278, 352718000)


def test_document_example_with_leap_seconds_is_18_s_earlier() -> None:
    assert gps_to_utc(2278, 352718000, apply_leap_seconds=True) == EXAMPLE_UTC - timedelta(
        seconds=18
    )
    assert utc_to_gps(EXAMPLE_UTC - timedelta(seconds=18), apply_leap_seconds=True) == (
        2278,
        352718000,
    )


def test_epoch_and_week_rollover() -> None:
    assert gps_to_utc(0, 0) == datetime(1980, 1, 6, tzinfo=UTC) == GPS_EPOCH
    assert utc_to_gps(GPS_EPOCH) == (0, 0)
    assert gps_to_utc(1, 0) == datetime(1980, 1, 13, tzinfo=UTC)
    assert utc_to_gps(datetime(1980, 1, 12, 23, 59, 59, 999000, tzinfo=UTC)) == (0, 604799999)


def test_other_time_zones_are_converted() -> None:
    beijing = timezone(timedelta(hours=8))
    assert utc_to_gps(EXAMPLE_UTC.astimezone(beijing)) == (2278, 352718000)


def test_naive_datetime_rejected() -> None:
    with pytest.raises(ValueError, match="naive"):
        utc_to_gps(datetime(2023, 9, 7, 1, 58, 38))


def test_before_epoch_rejected() -> None:
    with pytest.raises(ValueError, match="before the GPS epoch"):
        utc_to_gps(datetime(1980, 1, 5, tzinfo=UTC))


def test_leap_second_table_is_monotone_and_complete() -> None:
    dates = [d for d, _ in LEAP_SECONDS]
    counts = [n for _, n in LEAP_SECONDS]
    assert dates == sorted(dates)
    assert len(set(dates)) == len(dates)
    assert counts == list(range(1, len(counts) + 1))
    assert all(d.tzinfo is not None and d.day == 1 and d.month in (1, 7) for d in dates)
    assert counts[-1] == 18
    assert dates[-1] == datetime(2017, 1, 1, tzinfo=UTC)
    assert gps_minus_utc(GPS_EPOCH) == 0
    assert gps_minus_utc(datetime(2016, 12, 31, 23, 59, 59, 999999, tzinfo=UTC)) == 17
    assert gps_minus_utc(datetime(2017, 1, 1, tzinfo=UTC)) == 18


ms_datetimes = st.datetimes(
    min_value=datetime(1980, 1, 6),
    max_value=datetime(2200, 1, 1),
    timezones=st.just(UTC),
).map(lambda d: d.replace(microsecond=d.microsecond // 1000 * 1000))


@given(utc=ms_datetimes, leap=st.booleans())
def test_utc_roundtrip(utc: datetime, leap: bool) -> None:
    week, ms = utc_to_gps(utc, apply_leap_seconds=leap)
    assert 0 <= ms < 604_800_000
    assert gps_to_utc(week, ms, apply_leap_seconds=leap) == utc


@given(week=st.integers(0, 32767), ms=st.integers(0, 604_799_999))
def test_week_ms_roundtrip_document_rule(week: int, ms: int) -> None:
    assert utc_to_gps(gps_to_utc(week, ms)) == (week, ms)


@given(utc=ms_datetimes)
def test_leap_offset_is_the_table_value(utc: datetime) -> None:
    plain = utc_to_gps(utc)
    leap = utc_to_gps(utc, apply_leap_seconds=True)
    delta = (leap[0] - plain[0]) * 604_800_000 + leap[1] - plain[1]
    assert delta == 1000 * gps_minus_utc(utc)


def test_host_sub_frame_gnss_time() -> None:
    sub = HostSubFrame(gnss_week=2278, gnss_ms=352718000)
    assert sub.gnss_time() == EXAMPLE_UTC
    assert sub.gnss_time(apply_leap_seconds=True) == EXAMPLE_UTC - timedelta(seconds=18)
    built = HostSubFrame.build(
        latitude=0.0,
        longitude=0.0,
        altitude=0.0,
        gnss_time=EXAMPLE_UTC - timedelta(seconds=18),
        apply_leap_seconds=True,
    )
    assert (built.gnss_week, built.gnss_ms) == (2278, 352718000)
