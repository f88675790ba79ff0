"""GNSS week + ms ↔ UTC (Appendix 6): GPS time with leap seconds by default, the document's
rule (no leap seconds) on request; every encoder and decoder of the library agrees."""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import (
    AircraftState,
    HostPacket,
    HostSubFrame,
    decode_host_packet,
    gps_to_utc,
    utc_to_gps,
)
from gcu_async.protocol.gpstime import GPS_EPOCH, LEAP_SECONDS, gps_minus_utc

UTC = timezone.utc
EXAMPLE_UTC = datetime(2023, 9, 7, 1, 58, 38, tzinfo=UTC)


def test_document_example_without_leap_seconds() -> None:
    assert gps_to_utc(2278, 352718000, apply_leap_seconds=False) == EXAMPLE_UTC
    assert utc_to_gps(EXAMPLE_UTC, apply_leap_seconds=False) == (2278, 352718000)


def test_leap_seconds_are_the_default_both_ways_18_s_in_2023() -> None:
    assert gps_to_utc(2278, 352718000) == EXAMPLE_UTC - timedelta(seconds=18)
    assert utc_to_gps(EXAMPLE_UTC - timedelta(seconds=18)) == (2278, 352718000)
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
    assert utc_to_gps(EXAMPLE_UTC.astimezone(beijing), apply_leap_seconds=False) == (
        2278, 352718000)  # fmt: skip


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
    rule = {"apply_leap_seconds": False}
    assert utc_to_gps(gps_to_utc(week, ms, **rule), **rule) == (week, ms)


def _in_inserted_leap_second(week: int, ms: int) -> bool:
    """True for a GPS instant inside an inserted leap second (UTC 23:59:60)."""
    gps = GPS_EPOCH + timedelta(weeks=week, milliseconds=ms)
    return any(start + timedelta(seconds=n - 1) <= gps < start + timedelta(seconds=n)
               for start, n in LEAP_SECONDS)  # fmt: skip


@given(week=st.integers(0, 32767), ms=st.integers(0, 604_799_999))
def test_week_ms_roundtrip_with_leap_seconds(week: int, ms: int) -> None:
    back = utc_to_gps(gps_to_utc(week, ms))
    if _in_inserted_leap_second(week, ms):  # UTC 23:59:60 has no datetime: 1 s later
        assert back[0] * 604_800_000 + back[1] == week * 604_800_000 + ms + 1000
    else:
        assert back == (week, ms)


def test_the_leap_second_itself() -> None:
    # 2016-12-31T23:59:60 UTC is GPS 2017-01-01T00:00:17 (GPS - UTC went from 17 to 18 s)
    before = datetime(2016, 12, 31, 23, 59, 59, 500000, tzinfo=UTC)
    after = datetime(2017, 1, 1, 0, 0, 0, 500000, tzinfo=UTC)
    week, ms = utc_to_gps(before)
    assert utc_to_gps(after) == (week, ms + 2000)  # the inserted second lies between
    assert _in_inserted_leap_second(week, ms + 1000)
    assert not _in_inserted_leap_second(week, ms) and not _in_inserted_leap_second(week, ms + 2000)
    assert gps_to_utc(week, ms) == before
    assert gps_to_utc(week, ms + 1000) == after == gps_to_utc(week, ms + 2000)


@given(utc=ms_datetimes)
def test_leap_offset_is_the_table_value(utc: datetime) -> None:
    plain = utc_to_gps(utc, apply_leap_seconds=False)
    leap = utc_to_gps(utc, apply_leap_seconds=True)
    delta = (leap[0] - plain[0]) * 604_800_000 + leap[1] - plain[1]
    assert delta == 1000 * gps_minus_utc(utc)


def test_host_sub_frame_gnss_time() -> None:
    sub = HostSubFrame(gnss_week=2278, gnss_ms=352718000)
    assert sub.gnss_time(apply_leap_seconds=False) == EXAMPLE_UTC
    assert sub.gnss_time() == EXAMPLE_UTC - timedelta(seconds=18)
    assert sub.gnss_time(apply_leap_seconds=True) == EXAMPLE_UTC - timedelta(seconds=18)
    assert sub.as_dict()["gnss_time_utc"] == (EXAMPLE_UTC - timedelta(seconds=18)).isoformat()
    assert sub.as_dict()["gnss_time_document_rule"] == EXAMPLE_UTC.isoformat()
    built = HostSubFrame.build(
        latitude=0.0,
        longitude=0.0,
        altitude=0.0,
        gnss_time=EXAMPLE_UTC - timedelta(seconds=18),
        apply_leap_seconds=True,
    )
    assert (built.gnss_week, built.gnss_ms) == (2278, 352718000)


@given(utc=ms_datetimes.filter(lambda d: d.year < 2500))
def test_every_encoder_and_decoder_agree_on_leap_seconds(utc: datetime) -> None:
    # the encoders the library offers (the client's gnss_time= uses gnss_from_utc) and the
    # decoders (HostSubFrame.gnss_time, as_dict as `gcu-async decode` prints it) round-trip
    pair = utc_to_gps(utc)
    assert AircraftState.gnss_from_utc(utc) == pair
    built = HostSubFrame.build(latitude=0.0, longitude=0.0, altitude=0.0, gnss_time=utc)
    assert (built.gnss_week, built.gnss_ms) == pair
    state = AircraftState(position=(0.0, 0.0, 0.0), gnss_week=pair[0], gnss_ms=pair[1])
    wire = HostPacket(state.main_frame(), state.sub_frame()).encode()
    sub = decode_host_packet(wire).sub
    assert isinstance(sub, HostSubFrame)
    assert sub.gnss_time() == gps_to_utc(*pair) == utc
    assert sub.as_dict()["gnss_time_utc"] == utc.isoformat()
