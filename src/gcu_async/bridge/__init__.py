"""The XF gimbal and camera as standard MAVLink components (optional: ``gcu-async[mavlink]``).

:class:`MavlinkBridge` makes a GCU reachable from any MAVLink ground station or SDK as a
Gimbal Protocol v2 gimbal manager/device (``MAV_COMP_ID_GIMBAL``) and a Camera Protocol v2
camera (``MAV_COMP_ID_CAMERA``), and feeds the autopilot's state into the GCU's heartbeat
(docs/mavlink-bridge.md). The MAVLink ⇄ GCU mapping is pure
(:mod:`~gcu_async.bridge.gimbal`, :mod:`~gcu_async.bridge.camera`,
:mod:`~gcu_async.bridge.commands`, :mod:`~gcu_async.bridge.geometry`); the asyncio part
(:mod:`~gcu_async.bridge.bridge`, :mod:`~gcu_async.bridge.links`) only moves messages.
"""

from gcu_async.bridge.bridge import MavlinkBridge
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import CommandIn, GcuCall, Plan, result_for
from gcu_async.bridge.view import Control, GcuView

__all__ = ["CameraConfig", "CommandIn", "Control", "GcuCall", "GcuView", "MavlinkBridge",
           "Plan", "result_for"]
