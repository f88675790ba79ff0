"""Why a command failed: what the client knows that explains a GCU's failure status
(docs/client.md, "Why a command failed"), added to the :class:`CommandFailed` it raises."""

from __future__ import annotations

from gcu_async.errors import CommandFailed, LikelyCause
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import command_code
from gcu_async.protocol.commands import ZoomTo
from gcu_async.protocol.enums import PodModel, opcode_name
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports


def explain(error: CommandFailed, command: Command, model: PodModel | None, *, ins_invalid: bool,
            max_zoom: float | None, aircraft_timeout: float) -> None:  # fmt: skip
    """Add the likely cause of ``error`` (``command`` failed on a pod of ``model``), the
    first that holds: the pod model's Appendix 8 row, INS sent invalid (``ins_invalid``:
    packets went out with INS invalid while it was pending), camera 1's zoom limit."""
    opcode = command_code(command)
    name = opcode_name(opcode)
    if model is not None and model in POD_NAMES and not supports(model, opcode):
        error.explain(LikelyCause.NOT_SUPPORTED,
                      f"protocol Appendix 8: the {pod_name(model)} does not support "
                      f"{name}")  # fmt: skip
    elif ins_invalid:
        error.explain(LikelyCause.INS_INVALID,
                      f"{name} needs valid INS data and the host packets carried INS "
                      "invalid: give the aircraft's attitude, acceleration and velocity "
                      "with update_aircraft(), at most aircraft_timeout "
                      f"({aircraft_timeout:g} s) apart")  # fmt: skip
    elif (isinstance(command, ZoomTo) and command.ratio is not None
          and max_zoom is not None and command.ratio > max_zoom):  # fmt: skip
        error.explain(LikelyCause.ZOOM_LIMIT,
                      f"{command.ratio:g}x is beyond camera 1's maximum zoom "
                      f"{max_zoom:g}x")  # fmt: skip
