"""Compare the Lua dissector's items with ``gcu-async decode``'s JSON, field by field.

The dissector names its fields after decode's JSON: ``xfgcu.<host|gcu>.<path>`` where
``<path>`` is the JSON path (``main.aircraft_attitude_deg.roll``); a JSON list of numbers is
the same field repeated, in order (``main.aircraft_attitude_raw`` three times); ``None`` is a
field that is absent; a list of flag names is the set of bit fields under ``<path>`` whose
value is true; ``*_hex`` is a bytes field without the suffix; a command's ``params`` are
under the command's own name (``xfgcu.host.command.zoom_to.ratio``, :func:`params_prefix`).
The exceptions are listed in :data:`RENAMED`. Every leaf of the JSON must have its field,
every xfgcu field must map to a leaf or be one of the :data:`DISPLAY_ONLY` fields (checked on
their own here), and every value must agree: integers and strings exactly, reals as the
same double *and* printed with the digits decode prints (Python's repr) in the item's label.

Anomalies (docs/client.md, "Liberal receive, strict send"): decode's ``anomalies`` list and the
dissector's ``xfgcu.anomaly`` fields carry the same messages in the same order. For a command
decode flags (an ``AnomalousCommand``: raw parameters only), the dissector's engineering-unit
parameter fields are display-only; the raw parameters must still agree.
"""

from __future__ import annotations

import json
import re
from collections import defaultdict
from typing import Any

from gcu_async.protocol.enums import CameraMask
from gcu_async.protocol.pods import pod_name
from helpers.wireshark.tshark import Field, Frame, Item

FLAG_LISTS = {"pod_status", "faults", "thermal_flags", "camera_flags"}
RENAMED = {"xfgcu.host.sub.data_hex": "xfgcu.sub.data", "xfgcu.gcu.sub.data_hex": "xfgcu.sub.data"}
DISPLAY_ONLY = {
    "xfgcu.header", "xfgcu.length", "xfgcu.crc", "xfgcu.crc.computed", "xfgcu.crc.status",
    "xfgcu.reserved", "xfgcu.host.main.flags_reserved",
}  # fmt: skip
"""Fields decode's JSON has no key for; checked by :func:`check_display_only`."""
_CAMERA_BITS = re.compile(r"^xfgcu\.cameras\.camera_(\d)$")
_PARAM_CAMERAS = re.compile(r"^xfgcu\.host\.command\.\w+\.cameras$")


class Mismatch(AssertionError):
    pass


def expected_fields(obj: dict[str, Any]) -> tuple[dict[str, list[Any]], set[str], set[str]]:
    """From one decoded packet: {field: values in order}, the fields that must be absent,
    and the flag-list prefixes (``xfgcu.gcu.main.pod_status``)."""
    direction = "host" if obj["direction"] == "host_to_gcu" else "gcu"
    values: dict[str, list[Any]] = defaultdict(list)
    absent: set[str] = set()
    flags: dict[str, list[str]] = {}

    def walk(prefix: str, key: str, value: Any, command: str | None) -> None:
        name = f"{prefix}.{key}"
        if key == "params" and command is not None and isinstance(value, dict):
            name = params_prefix(command)  # each command's parameters: fields of their own
        if key.endswith("_hex"):
            name = RENAMED.get(name, name[: -len("_hex")])
            if value:
                values[name].append(bytes.fromhex(value))
            else:
                absent.add(name)
        elif value is None:
            absent.add(name)
        elif isinstance(value, dict):
            for k, v in value.items():
                walk(name, k, v, command)
        elif isinstance(value, list) and key in FLAG_LISTS:
            flags[name] = value
        elif isinstance(value, list):
            values[name].extend(value)
        else:
            values[name].append(value)

    values["xfgcu.direction"].append(obj["direction"])
    values["xfgcu.version"].append(obj["version"])
    for section in ("main", "sub", "command", "feedback"):
        if section in obj:
            command = obj[section].get("command") if section == "command" else None
            walk(f"xfgcu.{direction}", section, obj[section], command)
    values = {k: v for k, v in values.items() if v or k not in absent}
    return dict(values), absent, flags  # type: ignore[return-value]


def params_prefix(command: str) -> str:
    """Where the dissector puts the parameters of ``command`` (decode's name, ``ZOOM_TO``)."""
    return f"xfgcu.host.command.{command.lower()}"


def _same(field: Field, value: Any) -> bool:
    show = field.show
    if isinstance(value, bool):
        return show in ("1", "True") if value else show in ("0", "False")
    if isinstance(value, int):
        try:
            return int(show, 0) == value
        except ValueError:
            return False
    if isinstance(value, float):
        try:
            same = float(show) == value
        except ValueError:
            return False
        label = field.showname
        text = repr(value)  # decode prints json.dumps(value) == repr(value)
        shown = re.search(rf": {re.escape(text)}(?:$|[ ,)])", label) is not None
        return same and shown
    if isinstance(value, bytes):
        return bytes.fromhex(show.replace(":", "")) == value
    return bool(show == value)


def compare(obj: dict[str, Any], item: Item) -> list[str]:
    """Every disagreement between one decoded packet and one dissected item (empty: none)."""
    problems: list[str] = []
    want = [a["message"] for a in obj.get("anomalies", ())]
    got_anomalies = [f.show for f in item.named("xfgcu.anomaly")]
    if got_anomalies != want:
        problems.append(f"anomalies: decode {want}, dissector {got_anomalies}")
    if want and not item.has("xfgcu.anomaly.expert"):
        problems.append("anomalies without their expert info")
    # an AnomalousCommand has raw parameters only: the dissector's unit fields are extra
    unit_params = (params_prefix(obj["command"]["command"]) + "."
                   if "command" in obj and "params" not in obj["command"] else None)  # fmt: skip
    expected, absent, flags = expected_fields(obj)
    seen: dict[str, list[Field]] = defaultdict(list)
    for f in item.fields:
        if f.name.startswith("xfgcu."):
            seen[f.name].append(f)
    for name, values in expected.items():
        got = seen.get(name, [])
        if len(got) != len(values):
            problems.append(f"{name}: decode has {len(values)} value(s) {values!r}, "
                            f"the dissector {len(got)} {[g.show for g in got]!r}")  # fmt: skip
            continue
        for f, v in zip(got, values, strict=True):
            if not _same(f, v):
                want = v.hex() if isinstance(v, bytes) else json.dumps(v)
                problems.append(f"{name}: decode {want}, dissector {f.show!r} ({f.showname!r})")
    for name in absent:
        if name in seen:
            problems.append(f"{name}: decode has none, the dissector shows {seen[name][0].show!r}")
        if any(n.startswith(name + ".") for n in seen) and name.endswith(".sub"):
            problems.append(f"{name}: decode has no sub frame, the dissector shows one")
    flag_fields: set[str] = set()
    for prefix, names in flags.items():
        bits = [n for n in seen if n.startswith(prefix + ".")]
        flag_fields.update(bits)
        on = [n[len(prefix) + 1 :].upper() for n in bits if seen[n][0].show in ("1", "True")]
        if on != names:
            problems.append(f"{prefix}: decode {names}, dissector {on}")
        if not bits:
            problems.append(f"{prefix}: the dissector shows no bits")
    for name in seen:
        if (name in expected or name in flag_fields or name in DISPLAY_ONLY
                or _CAMERA_BITS.match(name)):  # fmt: skip
            continue
        if name.endswith((".bad", ".expert", ".nonzero", ".truncated")) or name == "xfgcu.anomaly":
            continue  # expert info, anomalies (compared above)
        if unit_params is not None and name.startswith(unit_params):
            continue
        problems.append(f"{name}: shown by the dissector, not in decode's JSON")
    problems += check_display_only(obj, seen)
    return problems


def check_display_only(obj: dict[str, Any], seen: dict[str, list[Field]]) -> list[str]:
    """The fields decode has no key for agree with what decode says."""
    problems: list[str] = []
    header = seen.get("xfgcu.header", [])
    want = 0xA8E5 if obj["direction"] == "host_to_gcu" else 0x8A5E
    if [int(f.show, 0) for f in header] != [want]:
        problems.append(f"header: {[f.show for f in header]}")
    if "sub" in obj and obj["sub"] and "pod_code" in obj["sub"]:
        vendor = [f.show for f in seen.get("xfgcu.gcu.sub.pod_model", [])]
        if vendor != [pod_name(obj["sub"]["pod_code"])]:
            problems.append(f"pod vendor name: {vendor} for code {obj['sub']['pod_code']}")
    masks = [int(f.show, 0) for name, fs in seen.items()
             if name == "xfgcu.gcu.feedback.failed_cameras" or _PARAM_CAMERAS.match(name)
             for f in fs]  # fmt: skip
    bits = [(int(m.group(1)), f.show) for name, fs in seen.items()
            if (m := _CAMERA_BITS.match(name)) for f in fs]  # fmt: skip
    if len(masks) == 1:
        on = sorted(n for n, show in bits if show in ("1", "True"))
        want_on = [n + 1 for n in range(8) if masks[0] & (1 << n)]
        if on != want_on or CameraMask(masks[0]) != sum(1 << (n - 1) for n in on):
            problems.append(f"camera bits {on} for mask {masks[0]:#x}")
    return problems


def packets_by_stream(frames: list[Frame]) -> dict[tuple[str, str, str], list[tuple[int, Item]]]:
    """The dissector's CRC-good packets (and malformed ones), per stream, in order."""
    out: dict[tuple[str, str, str], list[tuple[int, Item]]] = defaultdict(list)
    for frame in frames:
        for item in frame.items:
            if item.kind == "packet":
                out[frame.stream].append((frame.number, item))
    return out


Stream = tuple[str, str, str]


def decoded_by_stream(objs: list[dict[str, Any]]) -> dict[Stream, list[dict[str, Any]]]:
    out: dict[Stream, list[dict[str, Any]]] = defaultdict(list)
    for obj in objs:
        where = obj["capture"]
        out[(where["link"], where["src"], where["dst"])].append(obj)
    return out


def compare_capture(objs: list[dict[str, Any]], frames: list[Frame]) -> tuple[int, int]:
    """Both decoders agree on every packet of every stream; returns (packets, fields)
    compared. Raises :class:`Mismatch` listing the first disagreements."""
    ours, theirs = decoded_by_stream(objs), packets_by_stream(frames)
    problems: list[str] = []
    if set(ours) != set(theirs):
        problems.append(f"streams: decode {sorted(ours)}, dissector {sorted(theirs)}")
    packets = fields = 0
    for key in sorted(set(ours) & set(theirs)):
        a, b = ours[key], theirs[key]
        if len(a) != len(b):
            problems.append(f"{key}: decode found {len(a)} packets, the dissector {len(b)}")
        for index, (obj, (frame, item)) in enumerate(zip(a, b, strict=False)):
            if key[0] == "udp" and obj["capture"]["frame"] != frame:
                problems.append(f"{key} #{index}: frame {obj['capture']['frame']} vs {frame}")
            for p in compare(obj, item):
                problems.append(f"{key} #{index} (frame {frame}): {p}")
            packets += 1
            fields += len([f for f in item.fields if f.name.startswith("xfgcu.")])
    if problems:
        raise Mismatch(f"{len(problems)} disagreements, first ones:\n" + "\n".join(problems[:40]))
    return packets, fields
