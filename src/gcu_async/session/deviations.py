"""Saying once what a GCU does outside V2.0.6: a firmware deviation is logged the first time
a reply shows it, not per packet (every reply keeps its own in its ``anomalies``;
docs/client.md, "Liberal receive, strict send")."""

from __future__ import annotations

import logging

from gcu_async.protocol.anomalies import Anomaly

log = logging.getLogger("gcu_async.session")

FLAGGED_MAX = 64
"""Kinds of anomaly logged once each per session (a GCU sending junk cannot flood the log)."""


class DeviationLog:
    """The deviations of one link (named ``name`` in the log) already said."""

    __slots__ = ("_flagged", "name")

    def __init__(self, name: str) -> None:
        self.name = name
        self._flagged: set[tuple[str, str]] = set()
        """The kinds of anomaly (field, detail) already logged."""

    def other_version(self, version: int, count: int) -> None:
        """The ``count``-th reply of a version V2.0.6 does not define (decoded with its
        layout): the first is logged as a warning, the others only counted."""
        if count == 1:
            log.warning("%s: reply of protocol version %d (V2.0.6 defines 1 and 2): decoded "
                        "with the V2.0.6 layout; further ones are only counted "
                        "(link_health().other_versions)", self.name, version)  # fmt: skip

    def flag(self, anomalies: tuple[Anomaly, ...]) -> None:
        """Log each kind of value outside V2.0.6 (field and reading) the first time a reply
        carries it."""
        for anomaly in anomalies:
            key = (anomaly.field, anomaly.detail)
            if key in self._flagged or len(self._flagged) >= FLAGGED_MAX:
                continue
            self._flagged.add(key)
            log.warning("%s: the GCU sends a value outside V2.0.6, %s; said once, each reply "
                        "keeps it in its anomalies (docs/protocol-notes.md, \"What real pods "
                        "do\")", self.name, anomaly)  # fmt: skip
