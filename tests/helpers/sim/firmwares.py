"""Which tests run against every firmware the simulator plays (`gcu_async.sim.FIRMWARES`):
the client's, the bridge's and the web example's behaviour over real links, so a firmware
that departs from V2.0.6 (the Z-1Pro's signed camera yaw, its 72-byte null replies …) meets
every path a user takes. Argument checks and rate measurements do not depend on the
firmware and run against the document's only."""

from __future__ import annotations

import pytest

from gcu_async.sim import FIRMWARES

EVERY_FIRMWARE = {
    "test_client_behaviour.py", "test_client_waiting.py", "test_client_new_user.py",
    "test_client_wirelog.py",
    "test_bridge_gimbal.py", "test_bridge_camera.py", "test_bridge_command_rules.py",
    "test_bridge_autopilot.py", "test_bridge_gcu_outage.py",
    "test_example_web.py", "test_example_web_browser.py", "test_example_harness.py",
}  # fmt: skip
"""Test files whose simulator plays each firmware in turn (by file name: unique in the suite)."""


def parametrize(metafunc: pytest.Metafunc, argname: str, *, indirect: bool = False) -> None:
    """Run ``metafunc``'s test once per firmware through fixture ``argname`` (the pytest
    plugin's ``gcu_sim_firmware``, or a rig's: ``indirect``, its ``request.param``), if its
    file is listed and it uses that fixture."""
    if metafunc.definition.path.name in EVERY_FIRMWARE and argname in metafunc.fixturenames:
        metafunc.parametrize(argname, sorted(FIRMWARES), indirect=indirect)
