"""Which bridge component a command is for, and its plan (pure).

A command addressed to this system (or to every system) and to the gimbal or camera
component is planned by that component; an unknown command there is UNSUPPORTED. A
broadcast command (target component 0) is answered only when it is a request for a
message a bridge component serves (MAVSDK asks "any component" for
GIMBAL_MANAGER_INFORMATION), by that component. Commands for other components are ignored
(docs/mavlink-bridge.md, "Acknowledgements").
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

from gcu_async.bridge import camera, gimbal, streams
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import (
    ACCEPTED,
    DENIED,
    UNSUPPORTED,
    CommandIn,
    Plan,
    accept,
    refuse,
)
from gcu_async.bridge.view import GcuView

COMPONENTS = (gimbal.COMPONENT, camera.COMPONENT)
REQUEST_MESSAGE = mavlink.MAV_CMD_REQUEST_MESSAGE


def builders(component: int, config: CameraConfig) -> dict[int, Callable[[GcuView], Any]]:
    """Message id → ``builder(view)`` (``None`` when unavailable) of a component."""
    return _builders(component, config)


def _builders(component: int, config: CameraConfig) -> dict[int, Callable[[GcuView], Any]]:
    if component == gimbal.COMPONENT:
        return dict(gimbal.MESSAGES)
    return {mid: functools.partial(_with_config, builder, config)
            for mid, builder in camera.MESSAGES.items()}  # fmt: skip


def _with_config(builder: Callable[[GcuView, CameraConfig], Any], config: CameraConfig,
                 view: GcuView) -> Any:  # fmt: skip
    return builder(view, config)


def requested_id(cmd: CommandIn) -> int | None:
    """The message id a request command asks for (REQUEST_MESSAGE's param1, or the id a
    deprecated camera request command stands for); ``None`` for other commands."""
    if cmd.command == REQUEST_MESSAGE:
        value = cmd.param(1)
        return int(value) if math.isfinite(value) and 0 <= value <= 0xFFFFFF else -1
    return camera.LEGACY_REQUESTS.get(cmd.command)


def components_for(cmd: CommandIn, system_id: int, config: CameraConfig) -> tuple[int, ...]:
    """The bridge components that answer ``cmd`` (none, one, or for a broadcast request the
    component serving the message)."""
    if cmd.target_system not in (0, system_id):
        return ()
    if cmd.target_component in COMPONENTS:
        return (cmd.target_component,)
    if cmd.target_component != 0:
        return ()
    wanted = requested_id(cmd)
    if wanted is None:
        return ()
    return tuple(c for c in COMPONENTS if wanted in _builders(c, config))


def interval_plan(cmd: CommandIn, component: int, config: CameraConfig) -> Plan:
    """MAV_CMD_SET_MESSAGE_INTERVAL (param1 message id, param2 µs; :mod:`.streams`): for a
    message this component serves; UNSUPPORTED for others, DENIED for a bad interval."""
    value = cmd.param(1)
    message = int(value) if math.isfinite(value) else -1
    if message not in _builders(component, config):
        return refuse(UNSUPPORTED, f"message {value:g} is not served by component {component}")
    try:
        seconds = streams.interval_from_request(cmd.param(2))
    except ValueError as exc:
        return refuse(DENIED, str(exc))
    return Plan(ACCEPTED, interval=(message, seconds))


def plan(cmd: CommandIn, component: int, view: GcuView, config: CameraConfig) -> Plan:
    """The plan of ``component`` for ``cmd``. Malformed parameters (NaN where a number is
    needed, values out of every range) are DENIED, never raised."""
    try:
        return _plan(cmd, component, view, config)
    except (ValueError, TypeError, OverflowError) as exc:
        return refuse(DENIED, f"bad parameters: {exc}")


def _plan(cmd: CommandIn, component: int, view: GcuView, config: CameraConfig) -> Plan:
    if cmd.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
        return interval_plan(cmd, component, config)
    wanted = requested_id(cmd)
    if wanted is not None:
        builder = _builders(component, config).get(wanted)
        message = None if builder is None else builder(view)
        if message is None:
            return refuse(UNSUPPORTED, f"message {wanted} is not available here")
        return accept(message)
    if component == gimbal.COMPONENT:
        result = gimbal.command_plan(cmd, view)
    else:
        result = camera.command_plan(cmd, view, config)
    return result or refuse(UNSUPPORTED, f"command {cmd.command} is not supported")
