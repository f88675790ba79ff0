"""Firmware behaviours: how a simulated GCU fills its replies, one record per firmware.

Orthogonal to the pod model (:class:`~gcu_async.sim.profiles.PodProfile`: cameras, zoom,
the Appendix 8 support matrix): ``GcuSimulator(pod="Z-1Pro", firmware="z1pro-6.7")`` plays
the Z-1Pro whose replies were logged. The default, ``v2.0.6``, is the document. A firmware
other than the document's carries only behaviours that replies of real devices show; its
``evidence`` says where they come from and ``inferred`` what was filled in
(docs/protocol-notes.md, "What real pods do"; docs/simulator.md, "Firmware behaviours").
"""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_FIRMWARE = "v2.0.6"


@dataclass(frozen=True)
class Firmware:
    """One firmware's behaviours (each default: the document's)."""

    name: str
    """What ``--firmware`` and ``firmware=`` take."""
    summary: str
    """One line: what plays this firmware."""
    evidence: str
    """Where the behaviours come from."""
    inferred: str = ""
    """What the evidence does not show and the simulator assumes."""
    signed_yaw: bool = False
    """Camera absolute yaw (GCU bytes 22–23) sent as a signed S16 of half a turn either way
    (headings west of north from the field's
    :attr:`~gcu_async.protocol.headings.HeadingRule.signed_low` up) instead of V2.0.6's U16
    from 0 up to a full turn."""
    versions: tuple[float, float] | None = None
    """(hardware, firmware) versions the sub frame reports; ``None``: the pod profile's."""
    gnss_fault: bool = False
    """Fault bit 14 (GNSS not fixed) set until a host sub frame reports satellites."""
    missing_camera_zoom: float = 0.0
    """The zoom ratio the sub frame reports for a camera the pod does not have (camera 2 of
    a pod without a thermal camera): 0 (none) in the simulator's reading of the document."""
    centre_ignored_ok: bool = False
    """Centre (0x03) in a mode that ignores it (angle control, Euler control, FPV …) is
    answered 0x00 (success) instead of 0x01; the camera stays where it is."""

    @property
    def deviations(self) -> frozenset[str]:
        """Main-frame fields this firmware sends outside their V2.0.6 range (the simulator
        encodes them as they are: ``GcuPacket.encode(deviations=...)``)."""
        return frozenset({"yaw_raw"}) if self.signed_yaw else frozenset()


FIRMWARES: dict[str, Firmware] = {f.name: f for f in (
    Firmware(
        DEFAULT_FIRMWARE, "the document: every field as V2.0.6 gives it",
        "the GCU private protocol V2.0.6",
    ),
    Firmware(
        "z1pro-6.7", "a Z-1Pro reporting hardware 0.1, firmware 6.7",
        "68 CRC-valid replies of a Z-1Pro logged by crb12546/gogoguard_dog_end "
        "(z1pro_*_test/status.txt): signed camera yaw, hardware raw 1 and firmware raw 67, "
        "fault 0x4000 while the host sent no aircraft data, camera 2 (the Z-1Pro has none) "
        "at zoom 1x, centre in angle-control mode answered 0x00 with the camera left at -15 "
        "deg relative yaw",
        "that a host sub frame with satellites clears the GNSS fault (every logged host packet "
        "had none); that centre is answered so in every mode that ignores it (only angle "
        "control was logged)",
        signed_yaw=True, versions=(0.1, 6.7), gnss_fault=True, missing_camera_zoom=1.0,
        centre_ignored_ok=True,
    ),
)}  # fmt: skip
"""Every firmware the simulator plays, by name (docs/simulator.md: adding one)."""


def firmware_for(firmware: Firmware | str) -> Firmware:
    """A :class:`Firmware` itself, or the one :data:`FIRMWARES` names; ``ValueError`` lists
    the names for any other string, ``TypeError`` for anything else."""
    if isinstance(firmware, Firmware):
        return firmware
    if not isinstance(firmware, str):
        raise TypeError(f"firmware: expected a Firmware or one of {', '.join(FIRMWARES)}, got "
                        f"{type(firmware).__name__} {firmware!r}")  # fmt: skip
    found = FIRMWARES.get(firmware)
    if found is None:
        raise ValueError(f"firmware: {firmware!r} is not one of {', '.join(FIRMWARES)}")
    return found


__all__ = ["DEFAULT_FIRMWARE", "FIRMWARES", "Firmware", "firmware_for"]
