"""What ``gcu_async.sim`` exports: every part of :class:`~gcu_async.sim.SimState` (what a
test reads and stages through ``model.state``), so the generated reference documents the
fields a user reaches (``model.state.camera.photos``)."""

from __future__ import annotations

import dataclasses
import typing

import gcu_async.sim
from gcu_async.sim import SimState


def test_every_part_of_the_sim_state_is_exported() -> None:
    hints = typing.get_type_hints(SimState)
    parts = {
        hints[f.name] for f in dataclasses.fields(SimState)
        if isinstance(hints[f.name], type) and hints[f.name].__module__.startswith("gcu_async.sim")
    }  # fmt: skip
    assert {p.__name__ for p in parts} == {"CameraState", "Gimbal", "Rangefinder",
                                           "ReceivedAircraft"}  # fmt: skip
    for part in parts:
        assert part.__name__ in gcu_async.sim.__all__
        assert getattr(gcu_async.sim, part.__name__) is part


def test_all_names_exist_once() -> None:
    names = gcu_async.sim.__all__
    assert len(set(names)) == len(names)
    for name in names:
        assert hasattr(gcu_async.sim, name), name
