"""JSON views of the gimbal's state: one summary shape for ``/api/status`` and the telemetry
WebSocket, in engineering units, with the raw frames alongside."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from gcu_async import GcuClient, LinkEvent, LinkEventKind, LinkHealth
from gcu_async.client import ClientState
from gcu_async.protocol import AircraftState, Feedback, GcuMainFrame, GcuSubFrame, pod_name


def link_json(link: LinkHealth) -> dict[str, Any]:
    """Link health: ``up``, replies per second, age of the last reply (s) and counters."""
    data = asdict(link)
    if data["last_reply_age"] is not None:
        data["last_reply_age"] = round(data["last_reply_age"], 4)
    return data


def state_json(
    status: GcuMainFrame,
    info: GcuSubFrame | None,
    link: LinkHealth,
    feedback: Feedback | None = None,
    aircraft: AircraftState | None = None,
) -> dict[str, Any]:
    """The gimbal's state from the latest main frame (bytes 5–36), sub frame (bytes 37–68,
    ``None`` before the first) and link health; ``aircraft_heading`` is the aircraft yaw the
    host sends (host bytes 16–17), ``None`` while it sends none.

    Angles in degrees, rates in °/s, zoom as a ratio; ``raw`` holds both frames' raw wire
    integers and decoded fields (``as_dict()``).
    """
    attitude = status.attitude
    relative = status.relative_angles
    rates = status.angular_rates
    data: dict[str, Any] = {
        "mode": status.mode.name,
        "mode_raw": status.mode_raw,
        "attitude": {"roll": attitude.roll, "pitch": attitude.pitch, "yaw": attitude.yaw},
        "relative": {"x": relative.x, "y": relative.y, "z": relative.z},
        "rates": {"x": rates.x, "y": rates.y, "z": rates.z},
        "tracking": status.tracking_ok,
        "miss_distance": [status.miss_x, status.miss_y],
        "pod_status": status.as_dict()["pod_status"],
        "link": link_json(link),
        "aircraft_heading": None,
        "pod": None,
        "zoom": None,
        "recording": None,
        "target_distance_m": None,
        "flags": None,
        "raw": {"main": status.as_dict(), "sub": None},
    }
    if info is not None:
        sub = info.as_dict()
        data["pod"] = {
            "model": pod_name(info.pod_code),
            "code": info.pod_code,
            "hardware_version": info.hardware_version,
            "firmware_version": info.firmware_version,
        }
        data["zoom"] = {"camera1": info.camera1_zoom, "camera2": info.camera2_zoom}
        data["recording"] = info.recording
        data["target_distance_m"] = info.target_distance
        data["flags"] = {
            "camera": sub["camera_flags"],
            "thermal": sub["thermal_flags"],
            "faults": sub["faults"],
            "pip_mode": info.pip_mode,
        }
        data["raw"]["sub"] = sub
    if feedback is not None:
        data["feedback"] = feedback.as_dict()
    if aircraft is not None and aircraft.attitude is not None:
        data["aircraft_heading"] = aircraft.attitude.yaw
    return data


def client_state(gcu: GcuClient) -> dict[str, Any] | None:
    """:func:`state_json` of a client's latest status and info (``None`` before the first
    reply)."""
    if gcu.status is None:
        return None
    info = gcu.info if gcu.pod_model is not None else None
    return state_json(gcu.status, info, gcu.link, aircraft=gcu.aircraft)


class Attempts:
    """What the page says while the app waits for its GCU: the client's failed open
    attempts since it last came up (its ``RETRYING`` link events) and the last one's
    detail."""

    def __init__(self, gcu: GcuClient) -> None:
        self.gcu = gcu
        self.count = 0
        self.last: str | None = None
        gcu.on_link_change(self._event)

    def _event(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.RETRYING:
            self.count += 1
            self.last = event.detail
        elif event.kind is LinkEventKind.UP:
            self.count, self.last = 0, None

    def json(self) -> dict[str, Any]:
        """``state`` (the client's: ``opening``, ``open``, ``failed``, ``closed``), ``url``,
        failed ``attempts`` and ``last_error`` (the last attempt's, or why it failed)."""
        gcu = self.gcu
        failed = gcu.state is ClientState.FAILED
        return {"state": gcu.state.value, "url": gcu.transport.url, "attempts": self.count,
                "last_error": gcu.failure if failed else self.last}  # fmt: skip

    def describe(self) -> str:
        """One line for an error message: what the app waits for, or why it stopped."""
        gcu = self.gcu
        if gcu.state is ClientState.FAILED:
            return f"the client of the GCU at {gcu.transport.url} failed: {gcu.failure}"
        text = f"waiting for the GCU at {gcu.transport.url}"
        if self.count:
            text += f" ({self.count} failed attempt{'s' if self.count != 1 else ''}"
            text += f"; {self.last})" if self.last else ")"
        return text
