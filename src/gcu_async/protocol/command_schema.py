"""The words a command's schema is written in (:mod:`gcu_async.protocol.commands` uses them).

A command class's ``SCHEMA`` is a :class:`CommandSchema`: its parameters in wire order (each
a :class:`ParamKind`, whose kinds are in :mod:`gcu_async.protocol.command_fields`), the
client methods that send it (:class:`Method`), how its feedback's status reads
(:class:`StatusRule`), the mode it enters (:class:`ModeSpec`) and two flags. The catalogue
(:mod:`gcu_async.protocol.catalogue`) describes each method's parameters as a
:class:`Parameter` of a :class:`Kind`.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, NamedTuple

from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.enums import Mode
from gcu_async.protocol.fields import WireField


# -- the catalogue's description of a parameter (re-exported by protocol.catalogue) ---------
class Required(enum.Enum):
    """The marker of a parameter without a default (:data:`REQUIRED`)."""

    REQUIRED = "required"

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = Required.REQUIRED
"""``Parameter.default`` of a parameter the caller must give."""


class Kind(enum.Enum):
    """What a parameter takes (the package rule, :mod:`gcu_async.protocol`)."""

    REAL = "real"
    """A finite ``int`` or ``float`` in ``[low, high]``."""
    INTEGER = "integer"
    """An ``int`` (not a bool) in ``[low, high]``."""
    SWITCH = "switch"
    """``True`` or ``False``."""
    CAMERAS = "cameras"
    """A camera mask, an ``int`` in the range of
    :data:`~gcu_async.protocol.command_fields.CAMERA_MASK` (docs/protocol-notes.md §3
    "Camera masks")."""
    CHOICE = "choice"
    """A member of ``Parameter.choices`` or its exact value."""
    BOX = "box"
    """An :class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple of image fractions."""


@dataclass(frozen=True, slots=True)
class Parameter:
    """One parameter of a command method, as the caller writes it."""

    name: str
    kind: Kind
    doc: str
    """A few words: what it is, beyond unit and range."""
    unit: str = ""
    low: float | None = None
    """Smallest value (``None``: no numeric range: switches, boxes, choices)."""
    high: float | None = None
    low_open: bool = False
    """``low`` itself is excluded."""
    high_open: bool = False
    """``high`` itself is excluded."""
    default: object = REQUIRED
    choices: type[enum.IntEnum] | None = None
    """The enum of a :attr:`Kind.CHOICE` parameter."""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def range_text(self) -> str:
        """The range in words (``"<low> to <high>"``, ``"OFF, ON or AUTO"``), ``""`` if none."""
        if self.choices is not None:
            names = [m.name for m in self.choices]
            return f"{', '.join(names[:-1])} or {names[-1]}"
        if self.low is None or self.high is None:
            return ""
        low = f"{self.low:.12g}" + (" (excluded)" if self.low_open else "")
        high = "no limit" if math.isinf(self.high) else f"{self.high:.12g}"
        return f"{low} to {high}" + (" (excluded)" if self.high_open else "")


# -- what a command's schema says besides its parameters -----------------------------------
class StatusRule(enum.Enum):
    """How the execution status of a command's feedback reads (docs/protocol-notes.md §2
    "Execution status per command"); the value is the rule in words."""

    STANDARD = "0x00 success, any other value failure (0x01)"
    CALIBRATION = "0x00 success, 0x02 in progress (a later reply brings the result), else failure"
    THERMAL = "0x00 success, any other value failure (0x02)"
    ZOOM = "0x00 success, else the camera mask of the cameras that failed"


ControlReads = Literal["angles", "rates", "none"]
"""What a mode reads from the control values (session ``ControlKind`` values)."""


class ModeSpec(NamedTuple):
    """What a mode command does: the mode byte the GCU then reports (GCU main frame byte 5)
    and what that mode reads from the control values."""

    mode: Mode
    control: ControlReads


class Method(NamedTuple):
    """One client method (and ``gcu-async send`` subcommand) sending a command.

    ``params``: the method's parameters, each the name of a command attribute (a
    :class:`~gcu_async.protocol.command_fields.Point` gives ``x`` and ``y``) or an explicit
    :class:`Parameter` (control values, timeouts); ``None`` means every attribute in the
    class's order. ``required`` names the ones without a default though the class has one."""

    name: str
    doc: str
    params: tuple[str | Parameter, ...] | None = None
    required: tuple[str, ...] = ()


# -- a parameter of a command: the interface every kind implements -------------------------
@dataclass(frozen=True)
class ParamKind:
    """One parameter of a command: ``attrs`` of the class ↔ ``wire`` fields.

    A kind knows, once for every command that uses it, the send side (:meth:`encode`:
    attribute values → raw integers, checked), the receive side (:meth:`decode`, which raises
    ``ValueError`` for raw values V2.0.6 does not allow, and :meth:`anomalies`, which lists
    them), the JSON form and the catalogue's :class:`Parameter`."""

    attrs: tuple[str, ...] = field(init=False)
    """The command attributes it fills, in the class's order."""
    wire: tuple[WireField, ...] = field(init=False)
    """Its wire fields, in wire order."""
    normalizes: ClassVar[bool] = False
    """:meth:`normalize` stores a different value (a NamedTuple, an enum member)."""

    def normalize(self, value: Any) -> Any:
        """Send side: one attribute's value as it is stored (``TypeError`` if it cannot be)."""
        return value

    def encode(self, *values: Any) -> tuple[int, ...]:
        """Send side: the attributes' values → one raw integer per wire field, checked
        (``TypeError`` / :class:`~gcu_async.errors.FieldRangeError` naming the field)."""
        raise NotImplementedError

    def decode(self, *raw: int) -> tuple[Any, ...]:
        """Receive side: the raw integers → one value per attribute; ``ValueError`` for
        values V2.0.6 does not allow."""
        raise NotImplementedError

    def anomalies(self, *raw: int) -> tuple[Anomaly, ...]:
        """Receive side: every raw value outside what V2.0.6 allows (empty exactly when
        :meth:`decode` accepts them)."""
        found: tuple[Anomaly, ...] = ()
        for w, r in zip(self.wire, raw, strict=True):
            found += w.anomalies(r)
        return found

    def json(self, value: Any) -> Any:
        """One attribute's value for JSON output."""
        return value

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        """The catalogue's parameter(s), by name, given each attribute's default."""
        raise NotImplementedError

    def _set(self, attrs: tuple[str, ...], wire: tuple[WireField, ...]) -> None:
        object.__setattr__(self, "attrs", attrs)
        object.__setattr__(self, "wire", wire)


@dataclass(frozen=True, slots=True)
class CommandSchema:
    """Everything about one command but its opcode and attributes (the class has those)."""

    params: tuple[ParamKind, ...] = ()
    """The parameters in wire order."""
    methods: tuple[Method, ...] = ()
    """The client methods sending it, in the docs' order (none: the client sends it itself)."""
    status: StatusRule = StatusRule.STANDARD
    mode: ModeSpec | None = None
    """Set for a command that switches the pod's working mode."""
    needs_ins: bool = False
    """The GCU executes it only with valid aircraft INS data (host byte 11 B0)."""
    changes_mode: bool = False
    """Control values must be sent invalid while it is queued or in flight (besides the mode
    commands)."""

    @property
    def wire(self) -> tuple[WireField, ...]:
        return tuple(w for p in self.params for w in p.wire)
