"""This folder's simulators play every firmware where tests/helpers/sim/firmwares.py says so."""

from __future__ import annotations

import pytest

from helpers.sim.firmwares import parametrize


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    parametrize(metafunc, "gcu_sim_firmware")
