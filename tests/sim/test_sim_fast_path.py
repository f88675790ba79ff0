"""The simulator's fast path (the reply memo, gcu_async.sim.memo, and the exchange's datagram
shortcut) changes nothing but the time it takes: two simulators fed the same host traffic,
one with ``reply_memo`` on and one with it off, answer packet for packet with the same bytes
at the same times and end with the same counters, conformance report, executions and state.

The traffic is drawn by Hypothesis from a pool of requests (heartbeats of several kinds,
commands, anomalous and unknown commands, garbage, several packets in one datagram), with
long runs of repeats; between the packets time passes, faults are switched on and off, the
simulator is silenced and stalled, and the state is changed from outside as tests and
applications do. Exchanges and the stall switch run on a virtual loop in lockstep with each
simulator's ManualClock, so the comparison is exact.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from gcu_async.protocol import (
    HOST_HEADER,
    AngleControl,
    Attitude,
    Calibration,
    CameraMask,
    Centre,
    ClickToPan,
    ControlValues,
    DigitalZoom,
    EulerControl,
    Fpv,
    GazeAtCoordinates,
    GazeLock,
    GeoPosition,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    Mode,
    NightVision,
    NightVisionMode,
    PointingFollow,
    PointingLock,
    Ranging,
    Record,
    TakePhoto,
    TimeZone,
    TopDown,
    Track,
    ZoomIn,
    ZoomStop,
    ZoomTo,
)
from gcu_async.sim import FaultConfig, FaultPlan, GcuSimulator, ManualClock, SimulatorModel
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.motion import REL, Gimbal, Setpoint
from helpers.protocol.strategies import seal
from helpers.scale import scaled
from helpers.sim.support import host_bytes
from helpers.sim.timers import VirtualLoop


class Side:
    """One simulator (``memo`` on or off) behind one exchange, on its own clock."""

    def __init__(self, memo: bool, stream: bool) -> None:
        self.clock = ManualClock()
        self.sim = GcuSimulator(SimulatorModel(clock=self.clock, seed=7, reply_memo=memo))
        self.loop = VirtualLoop(self.clock, clamp=True)
        self.sim.stalls._loop = lambda: self.loop  # type: ignore[method-assign,assignment,return-value]
        self.exchange = Exchange(self.sim, stream=stream)
        self.exchange._loop = lambda: self.loop  # type: ignore[method-assign,assignment,return-value]
        self.sent: list[tuple[float, bytes]] = []
        self.replayed = 0
        model = self.sim.model
        replay = model.replay

        def counted(packet: bytes) -> bytes | None:
            reply = replay(packet)
            self.replayed += reply is not None
            return reply

        model.replay = counted  # type: ignore[method-assign]

    def send(self, data: bytes) -> None:
        self.sent.append((self.clock.now(), data))

    def feed(self, data: bytes) -> None:
        self.exchange.feed(data, self.send)

    def observed(self) -> dict[str, Any]:
        """Everything a user can read of the simulator, as plain data."""
        sim, model = self.sim, self.sim.model
        return {
            "sent": self.sent,
            "model": asdict(model.stats),
            "sim": asdict(sim.stats),
            "executions": dict(model.executions),
            "log": list(model.execution_log),
            "faults": (asdict(sim.request_faults.stats), asdict(sim.reply_faults.stats)),
            "stalled": (sim.stalled, sim.stalls.count),
            "silenced": sim.silenced,
            "state": model.state,
            "time": model._time,
            "last": (model.last_opcode, model._last_feedback),
            "report": model.conformance.report().as_dict(),
        }


def _raw(opcode: int, params: bytes = b"", version: int = 2, **kw: Any) -> bytes:
    """A CRC-valid host packet with any opcode, parameters and version."""
    return seal(HOST_HEADER, host_bytes(**kw)[5:69] + bytes([opcode]) + params, version)


def _yaw_out_of_range() -> bytes:
    body = bytearray(host_bytes()[5:69] + b"\x00")
    body[16 - 5 : 18 - 5] = (40000).to_bytes(2, "little")  # aircraft yaw >= 36000: flagged
    return seal(HOST_HEADER, bytes(body))


HEARTBEAT = host_bytes()
LONG = _raw(0x99, bytes(60))
GNSS = HostSubFrame.build(latitude=38.0, longitude=117.0, altitude=120.0, satellites=9,
                          relative_altitude=50.0)  # fmt: skip
REQUESTS: list[bytes] = [
    HEARTBEAT,
    HEARTBEAT,  # twice the weight: the idle host
    host_bytes(attitude=None),  # INS invalid
    host_bytes(attitude=(4.0, -3.0, 123.45)),  # the gimbal counter-rotates, then rests
    host_bytes(subframe_request=0),
    host_bytes(subframe_request=5),
    host_bytes(sub=GNSS),
    host_bytes(control=ControlValues.rates(yaw=20.0)),
    host_bytes(control=ControlValues.angles(pitch=-30.0, yaw=45.0)),
    host_bytes(TakePhoto()),
    host_bytes(Record()),
    host_bytes(ZoomIn()),
    host_bytes(ZoomStop()),
    host_bytes(ZoomTo(ratio=3.0)),
    host_bytes(ZoomTo(fraction=0.5, cameras=CameraMask.THERMAL)),
    host_bytes(Calibration()),
    host_bytes(Centre()),
    host_bytes(PointingLock()),
    host_bytes(PointingFollow()),
    host_bytes(AngleControl()),
    host_bytes(EulerControl()),
    host_bytes(Fpv()),
    host_bytes(TopDown()),
    host_bytes(GazeLock(), sub=GNSS),
    host_bytes(GazeAtCoordinates(latitude=38.001, longitude=117.001, altitude=0.0), sub=GNSS),
    host_bytes(Track(True, ImageBox(0.4, 0.4, 0.6, 0.6))),
    host_bytes(Track(False)),
    host_bytes(ClickToPan(ImagePoint(0.6, 0.4))),
    host_bytes(Ranging(True)),
    host_bytes(Ranging(True), sub=GNSS),
    host_bytes(Ranging(False)),
    host_bytes(NightVision(NightVisionMode.AUTO)),
    host_bytes(DigitalZoom(True)),
    host_bytes(TimeZone(3)),
    _raw(0x20, b"\x00"),  # photo with mask 0: anomalous, executed all the same
    _raw(0x08, b"\x0f"),  # time zone +15: anomalous, not executed
    _raw(0x00, b"\x01"),  # a null command with a parameter byte: still the separator
    _raw(0x99, b"\x01\x02"),  # an unknown opcode
    _raw(0x00, version=3),  # another version
    _yaw_out_of_range(),
    b"junk" + HEARTBEAT,
    HEARTBEAT[:40],
    HEARTBEAT + HEARTBEAT,
    HEARTBEAT[:-1] + bytes([HEARTBEAT[-1] ^ 1]),  # CRC error
    LONG,  # longer than a host packet may be (128 bytes): no packet in a datagram
]


def _set(path: str, value: Any) -> Callable[[SimulatorModel], None]:
    def apply(model: SimulatorModel) -> None:
        *parents, name = path.split(".")
        obj: Any = model
        for part in parents:
            obj = getattr(obj, part)
        setattr(obj, name, value)

    apply.__name__ = f"{path}={value!r}"
    return apply


def _direct(model: SimulatorModel) -> None:
    model.handle_bytes(LONG)  # what the model answers when handed a packet itself


def _in_place(model: SimulatorModel) -> None:
    model.state.gimbal.relative[2] += 1.0  # a list changed in place


def _setpoint(model: SimulatorModel) -> None:
    model.state.gimbal.setpoints[1].value = -10.0


def _drive(model: SimulatorModel) -> None:
    model.state.camera.zoom[1].value = 2.5


MUTATIONS: list[Callable[[SimulatorModel], None]] = [
    _set("state.camera.ambient_dark", True),
    _set("state.camera.ambient_dark", False),
    _set("state.faults", 0x0010),
    _set("state.inverted", True),
    _set("state.camera.scene_temperature", (-5.0, 60.0)),
    _set("state.rangefinder.noise", 0.0),
    _set("state.aircraft.relative_altitude", 30.0),
    _set("firmware", "z1pro-6.7"),
    _set("firmware", "v2.0.6"),
    _set("protocol_version", 1),
    _set("protocol_version", 2),
    _set("last_opcode", None),
    _in_place,
    _setpoint,
    _drive,
    _direct,
]

ODDS = st.sampled_from([0.0, 0.3])
FAULTS = st.none() | st.builds(
    FaultConfig, drop=ODDS, corrupt=ODDS, duplicate=ODDS, reorder=ODDS,
    delay=st.sampled_from([0.0, 0.03]), seed=st.integers(0, 99),
)  # fmt: skip
REQUEST = st.just(0) | st.integers(0, len(REQUESTS) - 1)
"""Half the time the heartbeat."""
GAPS = st.sampled_from([0.0, 0.001, 0.02, 0.02, 0.3])
SEND = st.tuples(st.just("send"), REQUEST, st.integers(1, 30), GAPS)
STEPS = st.one_of(
    SEND,
    SEND,
    SEND,  # half the steps
    st.tuples(st.just("wait"), st.sampled_from([0.0, 0.01, 0.5, 3.5])),
    st.tuples(st.just("faults"), FAULTS, st.sampled_from(["both", "requests", "replies"])),
    st.tuples(st.just("silence"), st.sampled_from([0.0, 0.05, 1.0])),
    st.tuples(st.just("stall"), st.sampled_from([0.0, 0.05, 0.3])),
    st.tuples(st.just("mutate"), st.integers(0, len(MUTATIONS) - 1)),
)


def run(steps: list[tuple[Any, ...]], stream: bool) -> tuple[Side, Side]:
    """The same steps on a simulator with the memo on and one with it off, compared after
    every step."""
    fast, full = Side(True, stream), Side(False, stream)
    for step in steps:
        for side in (fast, full):
            kind = step[0]
            if kind == "send":
                _, index, times, gap = step
                for _ in range(times):
                    side.feed(REQUESTS[index])
                    side.loop.advance(gap)
            elif kind == "wait":
                side.loop.advance(step[1])
            elif kind == "faults":
                config, where = step[1], step[2]
                side.sim.set_faults(None if config is None else FaultPlan(**{where: config})
                                    if where != "both" else config)  # fmt: skip
            elif kind == "silence":
                side.sim.silence(step[1])
            elif kind == "stall":
                side.sim.stall(step[1])
            else:
                MUTATIONS[step[1]](side.sim.model)
        assert fast.observed() == full.observed(), step
    assert full.replayed == 0
    return fast, full


@settings(max_examples=scaled(300, 30), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(steps=st.lists(STEPS, min_size=1, max_size=25), stream=st.booleans())
def test_the_fast_path_answers_as_the_full_path(steps: list[tuple[Any, ...]],
                                                stream: bool) -> None:  # fmt: skip
    fast, _ = run(steps, stream)
    event(f"replayed: {'some' if fast.replayed else 'none'}")


IDLE = [("send", 0, 20, 0.02)]


@pytest.mark.parametrize("stream", [False, True])
def test_an_idle_host_is_answered_from_the_memo(stream: bool) -> None:
    fast, full = run(IDLE, stream)
    assert fast.replayed == 19  # every heartbeat but the first
    assert fast.sim.model.stats.answered == full.sim.model.stats.answered == 20


@pytest.mark.parametrize(
    ("steps", "replayed"),
    [
        # a command runs in full; its first repeat too (the memo is made then: the
        # same-opcode rule's branch), the next ones come from the memo
        ([("send", 9, 5, 0.02)], 3),
        # moving: no memo while the zoom travels (29x at 7.25x/s: 4 s, 16 packets)
        ([("send", 11, 1, 0.25), ("send", 0, 16, 0.25)], 0),
        ([("send", 11, 1, 0.25), ("send", 0, 30, 0.25)], 14),
        # calibration repeated: its status comes from the clock, never from the memo
        ([("send", 15, 200, 0.02)], 0),
        # the rangefinder draws noise for every packet while it hits the ground (top-down)
        ([("send", 22, 1, 1.0), ("send", 28, 1, 0.02), ("send", 0, 20, 0.02)], 0),
        # ... and none while it sees no ground (the camera level): at rest
        ([("send", 28, 1, 0.02), ("send", 0, 20, 0.02)], 19),
        # a tilted aircraft: the gimbal counter-rotates (2 steps at 180 deg/s), then rests
        ([("send", 3, 30, 0.02)], 26),
        # rates in a rate mode move the camera: never at rest
        ([("send", 7, 30, 0.02)], 0),
        # faults: the exchange routes every packet (here: delays it), the model still
        # answers from the memo; silent, it processes nothing
        ([("send", 0, 3, 0.02), ("faults", FaultConfig(delay=0.001), "both"),
          ("send", 0, 10, 0.02)], 2 + 10),
        ([("send", 0, 3, 0.02), ("faults", FaultConfig(drop=0.5), "replies"),
          ("send", 0, 10, 0.02)], 2 + 10),
        ([("send", 0, 3, 0.02), ("faults", FaultConfig(drop=0.5), "requests"),
          ("send", 0, 10, 0.02)], lambda side: 2 + 10 - side.sim.request_faults.stats.dropped),
        ([("send", 0, 3, 0.02), ("silence", 1.0), ("send", 0, 10, 0.02)], 2),
        # heartbeats during a calibration run in full (its end is a state change)
        ([("send", 15, 1, 0.02), ("send", 0, 10, 0.02), ("wait", 3.5),
          ("send", 0, 5, 0.02)], 4),
        # a packet too long for a host packet (128 bytes) is no packet in a datagram, even
        # when the model, handed it directly, answered it (and made it its memo)
        ([("mutate", MUTATIONS.index(_direct)), ("mutate", MUTATIONS.index(_direct)),
          ("send", len(REQUESTS) - 1, 3, 0.02)], 0),
        # a stall: the 5 packets held are answered from the memo when it ends
        ([("send", 0, 2, 0.02), ("stall", 0.1), ("send", 0, 10, 0.02)], 11),
    ],
)
def test_when_the_memo_answers(steps: list[tuple[Any, ...]],
                               replayed: int | Callable[[Side], int]) -> None:  # fmt: skip
    fast, _ = run(steps, stream=False)
    assert fast.replayed == (replayed if isinstance(replayed, int) else replayed(fast))


SAME = ("state.camera.ambient_dark=False", "firmware='v2.0.6'", "protocol_version=2")
"""Mutations that set what the default state holds."""
CHANGES = [m for m in MUTATIONS if m.__name__ not in SAME and m is not _direct]


@pytest.mark.parametrize("change", CHANGES, ids=[m.__name__ for m in CHANGES])
def test_a_state_change_between_two_heartbeats_reaches_the_next_reply(
    change: Callable[[SimulatorModel], None],
) -> None:
    steps = [("send", 0, 3, 0.02), ("mutate", MUTATIONS.index(change)), ("send", 0, 1, 0.02)]
    fast, _ = run(steps, stream=False)
    assert fast.replayed == 2  # the heartbeat after the change took the full path


@pytest.mark.parametrize("stream", [False, True])
@pytest.mark.parametrize("method", ["handle", "handle_bytes", "encode"])
def test_overriding_the_model_turns_the_memo_off(method: str, stream: bool) -> None:
    side = Side(True, stream)
    for _ in range(3):
        side.feed(HEARTBEAT)
        side.loop.advance(0.02)
    assert side.replayed == 2
    calls: list[object] = []
    original = getattr(side.sim.model, method)

    def spy(arg: Any) -> Any:
        calls.append(arg)
        return original(arg)

    setattr(side.sim.model, method, spy)  # an application watching packets
    for _ in range(10):
        side.feed(HEARTBEAT)
        side.loop.advance(0.02)
    assert len(calls) == 10  # every packet
    assert side.replayed == 2
    delattr(side.sim.model, method)
    for _ in range(3):
        side.feed(HEARTBEAT)
        side.loop.advance(0.02)
    assert side.replayed == 2 + 3  # the memo made before still holds: nothing changed


@pytest.mark.parametrize("index", range(len(REQUESTS)))
def test_every_request_repeated(index: int) -> None:
    run([("send", 0, 3, 0.02), ("send", index, 6, 0.02), ("send", 0, 3, 0.02),
         ("send", index, 3, 0.3)], stream=False)  # fmt: skip


# -- the gimbal's rest, against its own step ----------------------------------------------
POSITION = GeoPosition(38.0, 117.0, 150.0)
PERTURB: dict[str, Callable[[Gimbal], None]] = {
    "none": lambda g: None,
    "gaze moving": lambda g: setattr(g, "gaze_moving", True),
    "pan here": lambda g: setattr(g, "pan", (g.absolute().pitch, g.absolute().yaw)),
    "pitch setpoint past its limit": lambda g: setattr(g.setpoints[1], "value", -95.0),
    "yaw setpoint at 360": lambda g: setattr(g.setpoints[2], "value", 360.0),
    "stale miss": lambda g: setattr(g, "miss", (5, -5)),
    "a rate": lambda g: g.rates.__setitem__(0, 0.5),
    "a control rate": lambda g: setattr(g, "control_rates", (0.0, 0.0, 1.0)),
    "an ulp off": lambda g: g.relative.__setitem__(1, g.relative[1] + 1e-13),
    "yaw at 180": lambda g: _yaw_at_180(g),
    "frozen here": lambda g: _frozen(g),
}


def _frozen(g: Gimbal) -> None:
    """Setpoints where the camera points, rates zero: held as it is (unless its mode aims
    elsewhere)."""
    g.setpoints = [Setpoint(f, g.current(axis, f)) for axis, f in enumerate(g.frames())]
    g.rates = [0.0, 0.0, 0.0]


def _yaw_at_180(g: Gimbal) -> None:
    """The motor yaw at +180 and its setpoint there: the step wraps it to -180."""
    g.relative[2] = 180.0
    frame = g.setpoints[2].frame
    g.setpoints[2] = Setpoint(frame, 180.0 if frame is REL else g.absolute().yaw)
    g.rates = [0.0, 0.0, 0.0]


SETUPS = ["mode", "gaze lock", "gaze at", "track", "track far", "pan", "angles", "angles far"]


@settings(max_examples=scaled(400, 40), deadline=None)
@example(Mode.GAZE, (0.0, 0.0, 0.0), POSITION, "mode", 0, "none", 1.0, 0.02)  # a point appears
@example(Mode.GAZE, (0.0, 0.0, 0.0), POSITION, "gaze at", 0, "frozen here", 1.0, 0.02)  # aim
@example(Mode.FPV, (0.0, 0.0, 0.0), None, "mode", 0, "yaw at 180", 1.0, 0.02)
@given(
    mode=st.sampled_from(sorted(set(Mode) - {Mode.UNKNOWN})),
    attitude=st.sampled_from([(0.0, 0.0, 0.0), (4.0, -3.0, 123.45), (-30.0, 60.0, 359.99)]),
    position=st.sampled_from([None, POSITION]),
    setup=st.sampled_from(SETUPS),
    converge=st.sampled_from([0, 1, 2, 5, 60]),
    perturb=st.sampled_from(sorted(PERTURB)),
    zoom=st.sampled_from([1.0, 7.5]),
    dt=st.sampled_from([1e-9, 0.001, 0.02, 1.0, 100.0]),
)
def test_a_settled_gimbal_is_left_as_it_is_by_a_step(
    mode: Mode, attitude: tuple[float, float, float], position: GeoPosition | None,
    setup: str, converge: int, perturb: str, zoom: float, dt: float,
) -> None:  # fmt: skip
    """:meth:`Gimbal.settled` against :meth:`Gimbal.step`: whatever state a run and a
    change from outside leave, a settled gimbal is left exactly as it is by a step of any
    length (the reply memo's definition of rest for the gimbal)."""
    aircraft = ReceivedAircraft(attitude=Attitude(*attitude), position=position)
    g = Gimbal(aircraft, mode=mode)
    if setup == "gaze lock":
        g.gaze_at(None)
    elif setup == "gaze at":
        g.gaze_at(GeoPosition(38.001, 117.002, 0.0))
    elif setup in ("track", "track far"):
        g.start_track(ImageBox(0.45, 0.45, 0.55, 0.55) if setup == "track" else
                      ImageBox(0.0, 0.0, 0.1, 0.05), zoom)  # fmt: skip
    elif setup == "pan":
        g.click_to_pan(ImagePoint(0.9, 0.1), zoom)
    elif setup.startswith("angles"):
        far = setup == "angles far"
        control = ControlValues.angles(roll=30.0 if far else 3.0, pitch=-150.0 if far else -20.0,
                                       yaw=170.0)  # fmt: skip
        g.control_input(control, True, zoom)
    for _ in range(converge):
        g.step(0.05, zoom)
    PERTURB[perturb](g)
    settled = g.settled(zoom)
    event(f"settled: {settled}")
    if settled:
        before = copy.deepcopy(g)
        g.step(dt, zoom)
        assert g == before
