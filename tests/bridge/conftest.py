"""The bridge rig's simulator plays every firmware where tests/helpers/sim/firmwares.py says so."""

from __future__ import annotations

import pytest

from gcu_async.sim import DEFAULT_FIRMWARE
from helpers.bridge import rig as rig_module
from helpers.sim.firmwares import parametrize


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    parametrize(metafunc, "rig_firmware", indirect=True)


@pytest.fixture(autouse=True)
def rig_firmware(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """The firmware :func:`helpers.bridge.rig.bridge_rig` starts its simulator with."""
    firmware = str(getattr(request, "param", DEFAULT_FIRMWARE))
    monkeypatch.setattr(rig_module, "FIRMWARE", firmware)
    return firmware
