"""What a real Z-1Pro (hardware 0.1, firmware 6.7) sends, as field values, and replies built
from them (docs/protocol-notes.md, "What real pods do").

The values were read off 68 CRC-valid replies that crb12546/gogoguard_dog_end logged
(``z1pro_*_test/status.txt``, the ``raw=`` fields); no log line is copied here. Every reply
had the values of :data:`SUB` and :data:`MAIN`; :data:`MOVES` are the 24 logged moves of more
than 5° of relative yaw: (relative Z before, camera yaw before, relative Z after, camera
yaw after), raw.
"""

from __future__ import annotations

from typing import Any

from gcu_async.protocol import Feedback, GcuMainFrame, GcuPacket, GcuSubFrame

SUB: dict[str, int] = {
    "hardware_version_raw": 1, "firmware_version_raw": 67, "pod_code": 49,
    "fault_raw": 0x4000, "target_distance_raw": 0, "camera1_zoom_raw": 10,
    "camera2_zoom_raw": 10, "thermal_flags_raw": 0, "camera_flags_raw": 0x6000, "time_zone": 8,
}  # fmt: skip
"""The sub frame of every logged reply (GNSS not fixed: the host sent no aircraft data)."""
MAIN: dict[str, int] = {"mode_raw": 0x10, "pod_status_raw": 0x1000}
"""The main frame's mode and pod status in every logged reply."""
VERSION = 2
MOVES: tuple[tuple[int, int, int, int], ...] = (
    (-1, 5591, 1443, 7064), (1509, 7143, -1438, 4319), (6, 8852, 13896, 51552),
    (14005, 51675, -8743, 65170), (-8743, 65170, -14018, 60584), (-14018, 60584, -211, 8684),
    (30, 54071, 2941, 57000), (3001, 57098, -2842, 50982), (-2945, 50890, 11902, 65321),
    (12000, 65456, -10500, 13714), (-10500, 13714, -12011, 12350), (-12011, 12350, -89, 53985),
    (37, 54124, 5979, 59823), (5979, 59823, -5959, 17590), (-5959, 17590, 28, 54228),
    (0, 7053, 2929, 9917), (3015, 10035, -2876, 4290), (-3006, 4150, 11668, 47664),
    (12005, 48093, -3286, 3975), (-3286, 3975, -12010, 60798), (-12010, 60798, -155, 7158),
    (2, 7344, 6000, 13051), (6000, 13051, -5996, 387), (-5996, 387, -1, 7369),
)  # fmt: skip
YAW_BANDS = ((387, 17590), (47664, 65456))
"""The raw camera yaws seen: these two bands and nothing in between."""
MOVE_AGREEMENT_DEG = 12.0
"""Read as S16, the change of heading of every move follows the change of relative yaw
within this (11.15° at most); read as U16, 10 of the 24 moves are off by 53–72°."""
FOCUS_STATUS = 0x01
"""Focus (0x26) answered failure: a fixed-focus pod (Appendix 8 agrees)."""


def main_frame(relative_z_raw: int = 0, yaw_raw: int = 0, **fields: int) -> GcuMainFrame:
    return GcuMainFrame(**{**MAIN, "relative_z_raw": relative_z_raw, "yaw_raw": yaw_raw,
                           **fields})  # fmt: skip


def reply(relative_z_raw: int = 0, yaw_raw: int = 0, *, opcode: int = 0,
          status: int | None = None, **fields: Any) -> bytes:  # fmt: skip
    """A Z-1Pro reply: 72 bytes to the null command, 73 with ``status`` to a command."""
    packet = GcuPacket(main_frame(relative_z_raw, yaw_raw, **fields), GcuSubFrame(**SUB),
                       Feedback(opcode, status), VERSION)  # fmt: skip
    return packet.encode(deviations={"yaw_raw"})
