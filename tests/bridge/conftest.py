"""The bridge rig's simulator plays every firmware where tests/_firmwares.py says so."""

from __future__ import annotations

import pytest

import _bridge_rig
from _firmwares import parametrize
from gcu_async.sim import DEFAULT_FIRMWARE


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    parametrize(metafunc, "rig_firmware", indirect=True)


@pytest.fixture(autouse=True)
def rig_firmware(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """The firmware :func:`_bridge_rig.bridge_rig` starts its simulator with."""
    firmware = str(getattr(request, "param", DEFAULT_FIRMWARE))
    monkeypatch.setattr(_bridge_rig, "FIRMWARE", firmware)
    return firmware
