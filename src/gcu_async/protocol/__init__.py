"""The sans-I/O protocol core of gcu_async: GCU private protocol V2.0.6.

No asyncio, sockets or serial here — bytes in, typed values out, and back. The simulator,
the client, the CLI and the tests all share this package.

**The rule for values users build.** Every public constructor, builder and function of this
package that takes user values checks type and range before anything is stored:

- a bool is a ``bool``: ``"false"``, ``0``, ``1`` and ``None`` raise ``TypeError``;
- an integer is an ``int``, not a bool, a float or a string (``IntEnum``/``IntFlag``
  members are ints and fine); camera masks are ints within the camera mask field's range
  (:data:`~gcu_async.protocol.command_fields.CAMERA_MASK`; ``CameraMask`` members fine);
- a real number is an ``int`` or ``float`` (not a bool) and finite: NaN, ±inf and values
  outside the wire range (``1e30``, ``10**40``) are :class:`~gcu_async.errors.FieldRangeError`;
- an enum parameter takes its members or their exact integer values;
- tuple parameters (``ImageBox``, ``ImagePoint``, ``Attitude``, ``NorthEastUp``,
  ``GeoPosition``, ``AxisAngles``) take their NamedTuple or a plain tuple of the same length
  (stored as the NamedTuple; lists and other NamedTuples raise ``TypeError``), checked
  element by element with the element in the field name (``box.left``, ``aircraft roll``).

Nothing is coerced, clipped or wrapped (real values are rounded to the wire resolution; a
command's parameter must lie in its range as given, a frame field's range applies to the
rounded value). Errors are ``TypeError`` or ``ValueError``
(usually :class:`~gcu_async.errors.FieldRangeError`) and name the field, the allowed range or
type, and the value. Frames, packets and ``ControlValues`` are NamedTuples that can be
built raw and cannot check themselves on construction: ``validate()`` / ``encode()`` check
them, and :meth:`ControlValues.check` is what a consumer calls before storing one.
Decoding is liberal by design: ``decode_*`` accept whatever the wire can carry; only a
wrong header, length or CRC raises, any other unexpected value is kept and flagged as an
:class:`Anomaly` (docs/client.md, "Liberal receive, strict send").
"""

from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.camera_axes import axes_to_euler, euler_to_axes
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import (
    AnomalousCommand,
    UnknownCommand,
    command_code,
    decode_command,
)
from gcu_async.protocol.commands import (
    COMMAND_TYPES,
    MODE_COMMANDS,
    AngleControl,
    AreaTemperature,
    Calibration,
    Centre,
    ClickToPan,
    DigitalZoom,
    EulerControl,
    FillLight,
    Focus,
    Fpv,
    GazeAtCoordinates,
    GazeLock,
    ImageAutoFlip,
    Isotherm,
    NightVision,
    NullCommand,
    Osd,
    OsdCoordinates,
    Palette,
    PictureInPicture,
    PointingFollow,
    PointingLock,
    Ranging,
    Record,
    SpotTemperature,
    TakePhoto,
    TargetDetection,
    TemperatureAlarm,
    TimeZone,
    TopDown,
    Track,
    ZoomIn,
    ZoomOut,
    ZoomStop,
    ZoomTo,
)
from gcu_async.protocol.crc import crc16_xmodem
from gcu_async.protocol.deframer import Deframer, DeframerStats
from gcu_async.protocol.enums import (
    CameraFlags,
    CameraMask,
    ExecutionStatus,
    FaultFlags,
    HostFlags,
    Mode,
    NightVisionMode,
    Opcode,
    OsdCoordinateSource,
    PodModel,
    PodStatus,
    SubFrameRequest,
    ThermalFlags,
    opcode_name,
)
from gcu_async.protocol.feedback import Feedback, failure_status, read_status
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame, UnknownSubFrame
from gcu_async.protocol.gpstime import gps_to_utc, utc_to_gps
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame
from gcu_async.protocol.packets import (
    GCU_HEADER,
    HOST_HEADER,
    GcuPacket,
    HostPacket,
    decode_gcu_packet,
    decode_host_packet,
    decode_packet,
)
from gcu_async.protocol.pods import (
    POD_NAMES,
    is_radiometric,
    is_thermal,
    pod_name,
    resolve_pod_model,
    supports,
)
from gcu_async.protocol.units import (
    Attitude,
    AxisAngles,
    GeoPosition,
    ImageBox,
    ImagePoint,
    NorthEastUp,
    wrap_degrees_180,
    wrap_degrees_360,
)

__all__ = [
    "COMMAND_TYPES",
    "GCU_HEADER",
    "HOST_HEADER",
    "MODE_COMMANDS",
    "POD_NAMES",
    "AircraftState",
    "AngleControl",
    "AnomalousCommand",
    "Anomaly",
    "AreaTemperature",
    "Attitude",
    "AxisAngles",
    "Calibration",
    "CameraFlags",
    "CameraMask",
    "Centre",
    "ClickToPan",
    "Command",
    "ControlValues",
    "Deframer",
    "DeframerStats",
    "DigitalZoom",
    "EulerControl",
    "ExecutionStatus",
    "FaultFlags",
    "Feedback",
    "FillLight",
    "Focus",
    "Fpv",
    "GazeAtCoordinates",
    "GazeLock",
    "GcuMainFrame",
    "GcuPacket",
    "GcuSubFrame",
    "GeoPosition",
    "HostFlags",
    "HostMainFrame",
    "HostPacket",
    "HostSubFrame",
    "ImageAutoFlip",
    "ImageBox",
    "ImagePoint",
    "Isotherm",
    "Mode",
    "NightVision",
    "NightVisionMode",
    "NorthEastUp",
    "NullCommand",
    "Opcode",
    "Osd",
    "OsdCoordinateSource",
    "OsdCoordinates",
    "Palette",
    "PictureInPicture",
    "PodModel",
    "PodStatus",
    "PointingFollow",
    "PointingLock",
    "Ranging",
    "Record",
    "SpotTemperature",
    "SubFrameRequest",
    "TakePhoto",
    "TargetDetection",
    "TemperatureAlarm",
    "ThermalFlags",
    "TimeZone",
    "TopDown",
    "Track",
    "UnknownCommand",
    "UnknownSubFrame",
    "ZoomIn",
    "ZoomOut",
    "ZoomStop",
    "ZoomTo",
    "axes_to_euler",
    "command_code",
    "crc16_xmodem",
    "decode_command",
    "decode_gcu_packet",
    "decode_host_packet",
    "decode_packet",
    "euler_to_axes",
    "failure_status",
    "gps_to_utc",
    "is_radiometric",
    "is_thermal",
    "opcode_name",
    "pod_name",
    "read_status",
    "resolve_pod_model",
    "supports",
    "utc_to_gps",
    "wrap_degrees_180",
    "wrap_degrees_360",
]  # fmt: skip
