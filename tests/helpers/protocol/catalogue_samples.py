"""A value for every catalogue parameter, made from its kind and range: tests that call a
command method with its required arguments take them from here, so a new command needs no
sample written for it."""

from __future__ import annotations

import math
from typing import Any

from gcu_async.protocol.catalogue import CatalogueEntry, Kind, Parameter

BOX = (0.4, 0.4, 0.6, 0.6)
"""A box inside the image, with room on every side."""


def sample(p: Parameter) -> Any:
    """A value of ``p`` well inside its range (the middle, on a coarse grid)."""
    if p.kind is Kind.SWITCH:
        return True
    if p.kind is Kind.BOX:
        return BOX
    if p.kind is Kind.CHOICE:
        assert p.choices is not None
        return next(iter(p.choices))
    assert p.low is not None and p.high is not None, p
    if p.kind in (Kind.INTEGER, Kind.CAMERAS):
        return int(p.low + p.high) // 2
    if math.isinf(p.high):
        return p.low + 1.0
    return round((p.low + p.high) / 2, 1)


def required_samples(entry: CatalogueEntry) -> dict[str, Any]:
    """A sample for each parameter of ``entry`` without a default."""
    return {p.name: sample(p) for p in entry.parameters if p.required}
