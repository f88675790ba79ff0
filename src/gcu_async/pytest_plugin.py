"""pytest plugin (entry point ``pytest11``): a running GCU simulator and a connected client.

Fixtures:

- ``gcu_sim`` — a :class:`SimHandle`: the :class:`~gcu_async.sim.GcuSimulator`, its running
  endpoint, the URL a client connects to, and fault switches.
- ``gcu_client`` — a :class:`~gcu_async.client.GcuClient` connected to ``gcu_sim`` (opened,
  heartbeat running, first reply received; closed after the test).

Choose the endpoint by overriding (or parametrizing) these fixtures:
``gcu_sim_transport`` (``"udp"`` default, ``"tcp"``, ``"serial"`` (a pty), ``"memory"``),
``gcu_sim_pod`` (default ``"D-90Pro(TA)"``), ``gcu_sim_firmware`` (default ``"v2.0.6"``,
the document; ``"z1pro-6.7"`` with the pod ``"Z-1Pro"`` plays a real Z-1Pro),
``gcu_sim_faults`` (``None`` or a :class:`~gcu_async.sim.FaultPlan` /
:class:`~gcu_async.sim.FaultConfig`), ``gcu_sim_seed``,
``gcu_sim_model_options`` (keyword arguments for :class:`~gcu_async.sim.SimulatorModel`,
e.g. ``calibration_seconds``), ``gcu_client_options`` (keyword arguments for the client).
Everything binds to 127.0.0.1 on ephemeral ports. The async fixtures need pytest-asyncio;
without it they skip.
"""

from __future__ import annotations

import inspect
import os
import sys
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import pytest

from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.sim.faults import FaultConfig, FaultPlan
from gcu_async.sim.firmware import DEFAULT_FIRMWARE
from gcu_async.sim.memory import MemoryServer
from gcu_async.sim.model import SimulatorModel
from gcu_async.sim.server import SimServer
from gcu_async.sim.simulator import GcuSimulator
from gcu_async.sim.tcp import TcpServer
from gcu_async.transport.registry import KINDS

TRANSPORTS = ("memory", *(k.scheme for k in KINDS.values() if k.fixture_listen is not None))
"""``gcu_sim_transport`` values: ``memory`` and every registered transport with a loopback
endpoint (:attr:`~gcu_async.transport.registry.TransportKind.fixture_listen`)."""
PTY_AVAILABLE = hasattr(os, "openpty") and sys.platform != "win32"
"""Can the ``"serial"`` transport (a pseudo-terminal and the POSIX serial client) run here?"""


@dataclass
class SimHandle:
    """A running simulator endpoint for one test."""

    simulator: GcuSimulator
    server: SimServer
    transport: str
    """``"memory"``, ``"udp"``, ``"tcp"`` or ``"serial"``."""

    @property
    def url(self) -> str:
        """Where a client connects (``udp://127.0.0.1:PORT``, ``serial:///dev/pts/N`` …)."""
        return self.server.url

    def client(self, **options: Any) -> GcuClient:
        """A new (unopened) client for this endpoint; ``async with`` it. The in-memory
        endpoint serves a single client."""
        if isinstance(self.server, MemoryServer):
            return GcuClient(self.server.transport, **options)
        for name, value in KINDS[self.transport].fixture_client.items():
            options.setdefault(name, value)
        return connect(self.url, **options)

    def set_faults(self, faults: FaultPlan | FaultConfig | None) -> None:
        """Replace the fault injection (``None`` clears it) from now on."""
        self.simulator.set_faults(faults)

    def silence(self, seconds: float) -> None:
        """The GCU stops answering for ``seconds``."""
        self.simulator.silence(seconds)

    def kill_connection(self) -> bool:
        """TCP only: drop the client's connection now; True if there was one."""
        if not isinstance(self.server, TcpServer):
            raise TypeError(f"kill_connection needs the tcp transport, not {self.transport}")
        return self.server.kill_connection()


def start_endpoint(sim: GcuSimulator, transport: str) -> SimServer:
    """The (not yet started) endpoint of ``sim`` for a transport name, on loopback."""
    if transport == "memory":  # no URL: the client takes the server's transport object
        return sim.serve_memory()
    kind = KINDS.get(transport)
    if kind is not None and kind.fixture_listen is not None:
        return sim.serve(kind.fixture_listen)
    raise ValueError(f"gcu_sim_transport: {transport!r} is not one of {', '.join(TRANSPORTS)}")


@pytest.fixture
def gcu_sim_transport() -> str:
    """Transport of the ``gcu_sim`` endpoint; override or parametrize."""
    return "udp"


@pytest.fixture
def gcu_sim_pod() -> str:
    """Pod model the simulator plays (Appendix 7 name or code)."""
    return "D-90Pro(TA)"


@pytest.fixture
def gcu_sim_firmware() -> str:
    """How the simulator fills its replies (:data:`gcu_async.sim.FIRMWARES`): the document,
    or a real device's firmware, e.g. ``"z1pro-6.7"`` (with ``gcu_sim_pod`` ``"Z-1Pro"``)."""
    return DEFAULT_FIRMWARE


@pytest.fixture
def gcu_sim_faults() -> FaultPlan | FaultConfig | None:
    """Fault injection for the simulator (``None``: a perfect link)."""
    return None


@pytest.fixture
def gcu_sim_seed() -> int:
    """Seed for the simulator's randomness."""
    return 0


@pytest.fixture
def gcu_sim_model_options() -> dict[str, Any]:
    """Keyword arguments for the simulator's model (``calibration_seconds``, ``max_zoom`` …)."""
    return {}


@pytest.fixture
def gcu_client_options() -> dict[str, Any]:
    """Keyword arguments for the ``gcu_client`` fixture's client."""
    return {}


_pytest_asyncio: Any
try:
    import pytest_asyncio as _pytest_asyncio
except ImportError:  # pragma: no cover - exercised only without pytest-asyncio
    _pytest_asyncio = None


def _async_fixture(func: Any) -> Any:
    """``pytest_asyncio.fixture``, or a fixture that skips when pytest-asyncio is missing.
    The skipping fixture takes the same fixtures as ``func``, so a test that overrides or
    parametrizes one of them (``gcu_sim_pod``) still collects, and skips."""
    if _pytest_asyncio is not None:
        return _pytest_asyncio.fixture(func)

    def skip(**fixtures: Any) -> None:
        pytest.skip(f"{func.__name__} needs pytest-asyncio (pip install 'gcu-async[pytest]')")

    params = [p.replace(annotation=inspect.Parameter.empty)
              for p in inspect.signature(func).parameters.values()]  # fmt: skip
    skip.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
    return pytest.fixture(name=func.__name__)(skip)


@_async_fixture
async def gcu_sim(
    gcu_sim_transport: str,
    gcu_sim_pod: str,
    gcu_sim_firmware: str,
    gcu_sim_faults: FaultPlan | FaultConfig | None,
    gcu_sim_seed: int,
    gcu_sim_model_options: dict[str, Any],
) -> AsyncIterator[SimHandle]:
    """A running simulator endpoint (see the module docstring). The ``"serial"`` transport
    is a pseudo-terminal, and both ends need POSIX: on Windows the test is skipped."""
    if gcu_sim_transport == "serial" and not PTY_AVAILABLE:
        pytest.skip("gcu_sim_transport 'serial' is a pseudo-terminal: POSIX only (not Windows)")
    model = SimulatorModel(gcu_sim_pod, seed=gcu_sim_seed, firmware=gcu_sim_firmware,
                           **gcu_sim_model_options)  # fmt: skip
    sim = GcuSimulator(model, faults=gcu_sim_faults)
    server = start_endpoint(sim, gcu_sim_transport)
    await server.open()
    try:
        yield SimHandle(sim, server, gcu_sim_transport)
    finally:
        await server.close()


@_async_fixture
async def gcu_client(
    gcu_sim: SimHandle, gcu_client_options: dict[str, Any]
) -> AsyncIterator[GcuClient]:
    """A client connected to ``gcu_sim``."""
    async with gcu_sim.client(**gcu_client_options) as client:
        yield client
