"""Run Debian's tshark with the package's dissector and read what it shows (PDML).

Every xfgcu item tshark shows (a packet, a span that failed its CRC, junk) is one
:class:`Item`; :func:`dissect` returns them per frame with the frame's stream key, in the
same form as ``gcu-async decode --file`` attributes packets to streams. tshark runs with a
private HOME, so a dissector installed in the real personal plugin folder is not loaded
twice, and its stderr and output are checked for Lua errors.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from gcu_async.wireshark import dissector_path

TSHARK = shutil.which("tshark")
TCPDUMP = shutil.which("tcpdump")
DUMPCAP = shutil.which("dumpcap")
TIMEOUT = 300.0
"""Seconds one tshark run may take (thousands of packets take a few)."""

needs_tshark = pytest.mark.skipif(
    TSHARK is None,
    reason="tshark is not installed (Debian package 'tshark'; `make test` installs it when "
    "CI=true and root)",
)


@dataclass
class Field:
    name: str
    show: str
    showname: str
    size: int


@dataclass
class Item:
    """One xfgcu tree of a frame: its fields depth-first, in display order."""

    fields: list[Field] = field(default_factory=list)

    def named(self, name: str) -> list[Field]:
        return [f for f in self.fields if f.name == name]

    def has(self, name: str) -> bool:
        return any(f.name == name for f in self.fields)

    @property
    def kind(self) -> str:
        """``packet`` (CRC good), ``bad`` (CRC mismatch) or ``junk``."""
        if self.has("xfgcu.junk"):
            return "junk"
        status = self.named("xfgcu.crc.status")
        return "packet" if status and status[0].show == "Good" else "bad"


@dataclass
class Frame:
    number: int
    stream: tuple[str, str, str]
    """(link, src, dst) as decode --file names them."""
    items: list[Item]
    expert: list[str]
    """Expert info messages of the frame."""


class LuaError(AssertionError):
    pass


def _fields(element: ET.Element, out: list[Field]) -> None:
    for child in element:
        if child.tag == "field":
            out.append(Field(child.get("name", ""), child.get("show", ""),
                             child.get("showname", ""), int(child.get("size", "0"))))  # fmt: skip
            _fields(child, out)
        elif child.tag == "proto":  # nested protocol items (none expected inside xfgcu)
            _fields(child, out)


def _first(packet: ET.Element, name: str) -> str | None:
    node = packet.find(f".//field[@name='{name}']")
    return None if node is None else node.get("show")


def _stream(packet: ET.Element) -> tuple[str, str, str]:
    serial = packet.find(".//proto[@name='xfgcu_serial']")
    if serial is not None:
        iface = _first(packet, "frame.interface_id") or "0"
        direction = _first(packet, "xfgcu_serial.direction") or "unknown"
        return ("serial", f"interface {iface}", direction)
    src = _first(packet, "ip.src") or _first(packet, "ipv6.src")
    dst = _first(packet, "ip.dst") or _first(packet, "ipv6.dst")
    six = _first(packet, "ip.src") is None

    def hostport(host: str | None, port: str | None) -> str:
        return f"[{host}]:{port}" if six else f"{host}:{port}"

    for link in ("tcp", "udp"):
        sport = _first(packet, f"{link}.srcport")
        if sport is not None:
            return (link, hostport(src, sport), hostport(dst, _first(packet, f"{link}.dstport")))
    return ("?", str(src), str(dst))


def run_tshark(capture: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    """tshark with the dissector on ``capture``; raises :class:`LuaError` on a Lua error."""
    assert TSHARK is not None
    with tempfile.TemporaryDirectory(prefix="gcu-tshark-home-") as home:
        env = {**os.environ, "HOME": home, "XDG_CONFIG_HOME": os.path.join(home, ".config")}
        done = subprocess.run(
            [TSHARK, "-n", "-X", f"lua_script:{dissector_path()}", "-r", str(capture), *extra],
            capture_output=True, text=True, timeout=TIMEOUT, env=env, check=False,
        )  # fmt: skip
    stderr = "\n".join(line for line in done.stderr.splitlines()
                       if "Running as user" not in line)  # fmt: skip
    if "Lua" in stderr or "lua" in stderr or done.returncode != 0:
        raise LuaError(f"tshark exit {done.returncode}: {stderr[:2000]}")
    if "Lua Error" in done.stdout or "_ws.lua.error" in done.stdout:
        raise LuaError("tshark showed a Lua error in the dissection")
    return done


def dissect(capture: Path, *extra: str) -> list[Frame]:
    """Every frame of ``capture`` that has xfgcu items, as tshark's PDML shows it
    (``extra``: more tshark options, e.g. ``-2``)."""
    done = run_tshark(capture, "-T", "pdml", *extra)
    root = ET.fromstring(done.stdout)
    frames: list[Frame] = []
    for packet in root.iter("packet"):
        protos = [p for p in packet.iter("proto") if p.get("name") == "xfgcu"]
        if not protos:
            continue
        items = []
        for proto in protos:
            item = Item()
            _fields(proto, item.fields)
            items.append(item)
        expert = [f.get("show", "") for f in packet.iter("field")
                  if f.get("name") == "_ws.expert.message"]  # fmt: skip
        number = int(_first(packet, "frame.number") or 0)
        frames.append(Frame(number, _stream(packet), items, expert))
    for frame in frames:
        for item in frame.items:
            assert not item.has("xfgcu.internal"), f"frame {frame.number}: dissector error"
    return frames


def verbose(capture: Path, frame_filter: str) -> str:
    """``tshark -O xfgcu -V`` text of the frames matching ``frame_filter``."""
    return run_tshark(capture, "-O", "xfgcu,xfgcu_serial", "-V", "-Y", frame_filter).stdout


def scratch_dir() -> Path:
    return Path(tempfile.mkdtemp(prefix="gcu-wireshark-"))
