"""Helpers for the simulator tests: packets built with the protocol core, a ManualClock rig
for the sans-I/O model, and bounded-wait socket peers for the servers."""

from __future__ import annotations

import asyncio
import contextlib
import os
from typing import Any, cast

from gcu_async.protocol import (
    AngleControl,
    AreaTemperature,
    Attitude,
    Calibration,
    CameraMask,
    Centre,
    ClickToPan,
    Command,
    ControlValues,
    Deframer,
    DigitalZoom,
    EulerControl,
    FillLight,
    Focus,
    Fpv,
    GazeAtCoordinates,
    GazeLock,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageAutoFlip,
    ImageBox,
    ImagePoint,
    Isotherm,
    NightVision,
    NightVisionMode,
    NullCommand,
    Osd,
    OsdCoordinates,
    OsdCoordinateSource,
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
    decode_gcu_packet,
)
from gcu_async.sim import ManualClock, SimulatorModel

LOOP = "127.0.0.1"

# Every command family in an order where each one's status is stable when run in sequence on
# the default D-90Pro(TA) (centre before the modes that ignore it, click-to-pan before
# tracking). Fill light is ○ for D-90Pro(TA) in Appendix 8: it must fail with 0x01.
FAMILIES: list[tuple[Command, int]] = [
    (Centre(), 0x00),
    (Calibration(), 0x02),
    (TakePhoto(), 0x00),
    (Record(), 0x00),
    (ZoomIn(), 0x00),
    (ZoomStop(), 0x00),
    (ZoomOut(), 0x00),
    (ZoomTo(ratio=10.0), 0x00),
    (ZoomTo(fraction=0.5, cameras=CameraMask.THERMAL), 0x00),
    (Focus(), 0x00),
    (Palette(3), 0x00),
    (NightVision(NightVisionMode.ON), 0x00),
    (AreaTemperature(True, ImageBox(0.1, 0.1, 0.5, 0.5)), 0x00),
    (TemperatureAlarm(True, high=40.0, low=10.0), 0x00),
    (Isotherm(True, high=30.0, low=20.0), 0x00),
    (SpotTemperature(True, ImagePoint(0.5, 0.5)), 0x00),
    (OsdCoordinates(OsdCoordinateSource.TARGET), 0x00),
    (ImageAutoFlip(False), 0x00),
    (TimeZone(8), 0x00),
    (Osd(True), 0x00),
    (PictureInPicture(2), 0x00),
    (TargetDetection(True), 0x00),
    (DigitalZoom(True), 0x00),
    (FillLight(128), 0x01),
    (Ranging(True), 0x00),
    (ClickToPan(ImagePoint(0.6, 0.4)), 0x00),
    (AngleControl(), 0x00),
    (PointingLock(), 0x00),
    (PointingFollow(), 0x00),
    (TopDown(), 0x00),
    (EulerControl(), 0x00),
    (Fpv(), 0x00),
    (GazeAtCoordinates(latitude=38.0, longitude=117.0, altitude=50.0), 0x00),
    (GazeLock(), 0x00),
    (Track(True, ImageBox(0.4, 0.4, 0.6, 0.6)), 0x00),
    (Track(False), 0x00),
]


def host_bytes(
    command: Command | None = None,
    *,
    control: ControlValues | None = None,
    attitude: tuple[float, float, float] | None = (0.0, 0.0, 0.0),
    sub: HostSubFrame | None = None,
    subframe_request: int = 1,
    version: int = 2,
) -> bytes:
    """One encoded host packet (INS valid with a level aircraft at rest facing north by
    default; ``attitude=None``: INS invalid)."""
    still = None if attitude is None else (0.0, 0.0, 0.0)  # INS valid needs all three parts
    main = HostMainFrame.build(control=control, attitude=attitude, acceleration=still,
                               velocity=still, subframe_request=subframe_request)  # fmt: skip
    return HostPacket(main, sub, command or NullCommand(), version).encode()


def sub_of(reply: GcuPacket) -> GcuSubFrame:
    """The reply's standard sub frame (fails the test when there is none)."""
    assert isinstance(reply.sub, GcuSubFrame), reply.sub
    return reply.sub


class Rig:
    """A model on a ManualClock, driven like a host that sends at ``hz``."""

    def __init__(self, pod: str = "D-90Pro(TA)", hz: float = 50.0, **kw: Any) -> None:
        self.clock = ManualClock()
        self.model = SimulatorModel(pod, clock=self.clock, **kw)
        self.hz = hz
        self.control: ControlValues | None = None
        self.attitude: tuple[float, float, float] | None = (0.0, 0.0, 0.0)
        self.sub: HostSubFrame | None = None

    def send(self, command: Command | None = None, **kw: Any) -> GcuPacket:
        """One packet carrying the rig's current control/attitude; exactly one reply."""
        kw.setdefault("control", self.control)
        kw.setdefault("attitude", self.attitude)
        kw.setdefault("sub", self.sub)
        replies = self.model.receive(host_bytes(command, **kw))
        assert len(replies) == 1, replies
        return decode_gcu_packet(replies[0])

    def null(self) -> GcuPacket:
        return self.send(NullCommand())

    def run(self, seconds: float) -> GcuPacket:
        """Keep sending null packets for ``seconds`` of clock time; the last reply."""
        steps = max(1, round(seconds * self.hz))
        reply = self.null()
        for _ in range(steps):
            self.clock.advance(1.0 / self.hz)
            reply = self.null()
        return reply

    def command(self, command: Command) -> GcuPacket:
        """Send ``command`` after a null packet, so the same-opcode rule never swallows it."""
        self.null()
        return self.send(command)

    @property
    def attitude_now(self) -> Attitude:
        return self.model.state.attitude


class UdpPeer(asyncio.DatagramProtocol):
    """A host on a real UDP socket: bounded waits for GCU replies."""

    def __init__(self) -> None:
        self.transport: asyncio.DatagramTransport | None = None
        self.queue: asyncio.Queue[tuple[bytes, tuple[str, int]]] = asyncio.Queue()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.queue.put_nowait((data, (addr[0], addr[1])))

    @classmethod
    async def open(cls) -> UdpPeer:
        loop = asyncio.get_running_loop()
        _, peer = await loop.create_datagram_endpoint(cls, local_addr=(LOOP, 0))
        return peer

    @property
    def address(self) -> tuple[str, int]:
        assert self.transport is not None
        host, port = self.transport.get_extra_info("sockname")[:2]
        return host, port

    def send(self, data: bytes, addr: tuple[str, int]) -> None:
        assert self.transport is not None
        self.transport.sendto(data, addr)

    async def receive(self, timeout: float = 2.0) -> tuple[bytes, tuple[str, int]]:
        return await asyncio.wait_for(self.queue.get(), timeout)

    async def request(self, data: bytes, addr: tuple[str, int], timeout: float = 2.0) -> GcuPacket:
        self.send(data, addr)
        reply, _ = await self.receive(timeout)
        return decode_gcu_packet(reply)

    async def nothing(self, within: float = 0.2) -> bool:
        """True when no datagram arrives within ``within`` seconds."""
        try:
            await asyncio.wait_for(self.queue.get(), within)
        except asyncio.TimeoutError:
            return True
        return False

    async def close(self) -> None:
        if self.transport is not None:
            self.transport.close()
            await asyncio.sleep(0)


class StreamPeer:
    """A host on a byte stream (TCP): deframes replies, bounded waits."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer
        self.deframer = Deframer.for_gcu_packets()
        self.pending: list[bytes] = []

    @classmethod
    async def connect(cls, address: tuple[str, int]) -> StreamPeer:
        reader, writer = await asyncio.wait_for(asyncio.open_connection(*address), 2.0)
        return cls(reader, writer)

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        async def next_packet() -> bytes:
            while not self.pending:
                data = await self.reader.read(4096)
                if not data:
                    raise ConnectionError("closed")
                self.pending += self.deframer.feed(data)
            return self.pending.pop(0)

        return decode_gcu_packet(await asyncio.wait_for(next_packet(), timeout))

    async def request(self, data: bytes, timeout: float = 2.0) -> GcuPacket:
        self.writer.write(data)
        return await self.reply(timeout)

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(ConnectionError, OSError):
            await asyncio.wait_for(self.writer.wait_closed(), 2.0)


class FdPeer:
    """A host on a terminal file descriptor (pty side or device): bounded waits."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        os.set_blocking(fd, False)
        self.deframer = Deframer.for_gcu_packets()
        self.queue: asyncio.Queue[bytes] = asyncio.Queue()
        asyncio.get_running_loop().add_reader(fd, self._readable)

    @classmethod
    def open_path(cls, path: str) -> FdPeer:
        """Open a serial device path the way a client would (raw, no controlling tty).
        POSIX only (the callers skip on Windows)."""
        import tty

        fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        return cls(fd)

    def _readable(self) -> None:
        try:
            data = os.read(self.fd, 4096)
        except (BlockingIOError, OSError):
            return
        for packet in self.deframer.feed(data):
            self.queue.put_nowait(packet)

    def send(self, data: bytes) -> None:
        os.write(self.fd, data)

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        return decode_gcu_packet(await asyncio.wait_for(self.queue.get(), timeout))

    async def request(self, data: bytes, timeout: float = 2.0) -> GcuPacket:
        self.send(data)
        return await self.reply(timeout)

    def close(self) -> None:
        asyncio.get_running_loop().remove_reader(self.fd)
        os.close(self.fd)


def tagged(i: int, command: Command | None = None) -> bytes:
    """Host packet number ``i``: the aircraft yaw (i degrees) comes back in the reply, so a
    reply tells which request it answers (:func:`tag`)."""
    return host_bytes(command, attitude=(0.0, 0.0, float(i)))


def tag(reply: GcuPacket) -> int:
    """The number of the request :func:`tagged` made, read from its reply."""
    return round(reply.main.attitude.yaw)


async def eventually(predicate: Any, timeout: float = 2.0) -> None:
    """Wait until ``predicate()`` holds, polling every 5 ms; TimeoutError after ``timeout``."""
    deadline = asyncio.get_running_loop().time() + timeout
    while not predicate():
        if asyncio.get_running_loop().time() > deadline:
            raise TimeoutError("condition not met in time")
        await asyncio.sleep(0.005)

