"""Hostile command bodies for the web example: hypothesis over JSON a client should never
send (huge integers, deep nesting, NaN and infinities, wrong types, unknown keys, bytes
that are not JSON) always gets a 4xx naming what is wrong, never a 500, and the simulated
GCU executes nothing; and the body limit holds memory down while an endless body streams
into the real entry point (``python -m examples.web --sim``, a subprocess whose RSS is
sampled from /proc).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from helpers.examples.web_deps import require_web

require_web()
import httpx  # noqa: E402

from gcu_async.sim import GcuSimulator  # noqa: E402
from helpers.examples.web import Web, running_web  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
START_TIMEOUT = 15.0


# -- a running app for synchronous hypothesis tests -------------------------------------
class ThreadedWeb:
    """The app and a simulator on their own event loop in a thread."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self.ready = threading.Event()
        self.web: Web | None = None
        self.sim = GcuSimulator()
        self.failure: BaseException | None = None
        self.http: Any = None
        """A synchronous ``httpx.Client`` on the app (set by the fixture)."""
        self._stop: asyncio.Event | None = None
        self.thread = threading.Thread(target=self._run, name="web-app", daemon=True)

    def _run(self) -> None:
        try:
            self.loop.run_until_complete(self._main())
        except BaseException as exc:  # reported by the fixture
            self.failure = exc
            self.ready.set()
        finally:
            self.loop.close()

    async def _main(self) -> None:
        self._stop = asyncio.Event()
        async with self.sim.serve_udp("127.0.0.1", 0) as server, \
                running_web(server.url, None) as web:  # fmt: skip
            self.web = web
            self.ready.set()
            await self._stop.wait()

    def stop(self) -> None:
        if self._stop is not None:
            self.loop.call_soon_threadsafe(self._stop.set)
        self.thread.join(START_TIMEOUT)

    @property
    def executed(self) -> int:
        return sum(self.sim.model.executions.values())


@pytest.fixture(scope="module")
def threaded_web() -> Iterator[ThreadedWeb]:
    running = ThreadedWeb()
    running.thread.start()
    assert running.ready.wait(START_TIMEOUT), "the app did not start"
    if running.failure is not None:
        raise running.failure
    assert running.web is not None
    # one HTTP client for every example (making one loads the CA bundle: slow)
    with httpx.Client(base_url=running.web.base_url, timeout=10.0) as http:
        running.http = http
        try:
            yield running
        finally:
            running.stop()


# -- hostile values ------------------------------------------------------------------------
HUGE = st.integers(min_value=10**18, max_value=10**4000) | st.integers(
    min_value=-(10**4000), max_value=-(10**18)
)
"""Integers outside every parameter range (calibrate's open-ended timeout is left out)."""
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])
OUT_OF_RANGE_FLOAT = st.floats(min_value=1e7, allow_nan=False, allow_infinity=False) | st.floats(
    max_value=-1e7, allow_nan=False, allow_infinity=False
)
WRONG_TYPE: st.SearchStrategy[Any] = (
    st.none() | st.booleans() | st.text(max_size=20) | st.just({}) | st.just([])
)
SCALAR = HUGE | NON_FINITE | OUT_OF_RANGE_FLOAT | WRONG_TYPE
NESTED = st.recursive(SCALAR, lambda inner: st.lists(inner, max_size=4)
                      | st.dictionaries(st.text(max_size=5), inner, max_size=3),
                      max_leaves=12)  # fmt: skip
TARGETS = [("zoom_to", "ratio"), ("enter_euler_control", "pitch"), ("enter_euler_control", "yaw"),
           ("take_photo", "cameras"), ("track", "box"), ("set_fill_light", "brightness"),
           ("set_night_vision", "mode"), ("set_palette", "palette"),
           ("enter_pointing_lock", "yaw_rate"), ("gaze_at", "altitude")]  # fmt: skip


@st.composite
def hostile_bodies(draw: st.DrawFn) -> tuple[str, bytes, str | None]:
    """``(command, body, name the error must mention or None)``."""
    name, param = draw(st.sampled_from(TARGETS))
    shape = draw(st.sampled_from(["value", "nested", "extra", "deep", "top", "raw"]))
    if shape == "value":
        return name, json.dumps({param: draw(SCALAR)}).encode(), param
    if shape == "nested":
        value = draw(NESTED.filter(lambda v: isinstance(v, (list, dict))))
        return name, json.dumps({param: value}).encode(), param
    if shape == "extra":  # an unknown key beside a hostile value
        key = draw(st.text(min_size=1, max_size=8).filter(lambda k: k != param))
        return name, json.dumps({param: draw(SCALAR), key: draw(NESTED)}).encode(), None
    if shape == "deep":
        depth = draw(st.integers(min_value=9, max_value=8000))
        opener = draw(st.sampled_from(["[", '{"a":']))
        return name, (opener * depth).encode()[:16000], "nesting depth"
    if shape == "top":  # not an object
        value = draw(NESTED.filter(lambda v: not isinstance(v, dict)))
        return name, json.dumps(value).encode(), "must be a JSON object"
    raw = draw(st.binary(min_size=1, max_size=200).filter(lambda b: b.strip()))
    return "zoom_to", raw, None  # zoom_to needs ratio: no raw body is a valid call


@settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                HealthCheck.too_slow])  # fmt: skip
@given(case=hostile_bodies())
def test_hostile_bodies_are_4xx_naming_the_problem(
    threaded_web: ThreadedWeb, case: tuple[str, bytes, str | None]
) -> None:
    web = threaded_web.web
    assert web is not None
    name, body, mention = case
    response = threaded_web.http.post(f"/api/commands/{name}", content=body,
                                      headers={"content-type": "application/json"})  # fmt: skip
    assert response.status_code in (400, 413, 422), (body[:200], response.text[:500])
    answer = response.json()
    assert isinstance(answer["error"], str) and answer["error"], answer
    assert answer["kind"] in ("BadRequest", "PayloadTooLarge", "ValueError", "FieldRangeError")
    if response.status_code == 413:  # huge integers can make the body itself too long
        assert len(body) > 16384 and "allowed range [0, 16384] bytes" in answer["error"]
    elif mention is not None:
        assert mention in answer["error"], (body[:200], answer)
    assert threaded_web.executed == 0


# -- the body limit bounds memory ----------------------------------------------------------
def _rss_mib(pid: int) -> float:
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise AssertionError(f"no VmRSS for {pid}")


def _free_tcp_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@pytest.fixture
def console() -> Iterator[tuple[subprocess.Popen[str], int]]:
    """``python -m examples.web --sim`` on a free port: the real entry point."""
    if not Path("/proc/self/status").exists():
        pytest.skip("RSS is read from /proc (Linux)")
    port = _free_tcp_port()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    env.pop("GCU_WEB_TOKEN", None)
    process = subprocess.Popen(
        [sys.executable, "-m", "examples.web", "--sim", "--port", str(port)],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while True:
            with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
                break
            assert process.poll() is None, process.communicate()[0]
            assert time.monotonic() < deadline, "the console did not start"
            time.sleep(0.05)
        yield process, port
    finally:
        process.terminate()
        try:
            process.communicate(timeout=START_TIMEOUT)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()


STREAM_BYTES = 128 * 2**20
"""How much an endless body offers: 128 MiB (the finding: 256 MiB took RSS +512 MiB)."""
RSS_GROWTH_MIB = 16.0
"""The most the server's RSS may grow while the body streams (the limit is 16 KiB)."""


def _stream(port: int, head: bytes, chunk: bytes, result: dict[str, Any]) -> None:
    """Send ``head`` then ``chunk`` until STREAM_BYTES or the server stops taking it, while
    collecting what the server answers. Bounded: 2 s per send, 30 s in all."""
    answer = b""
    sent = 0
    deadline = time.monotonic() + 30.0
    with socket.create_connection(("127.0.0.1", port), timeout=2.0) as sock:
        sock.sendall(head)
        result["head_sent"] = time.monotonic()
        try:
            while sent < STREAM_BYTES and time.monotonic() < deadline and not result.get("stop"):
                sock.sendall(chunk)
                sent += len(chunk)
                sock.setblocking(False)
                with contextlib.suppress(BlockingIOError):
                    data = sock.recv(65536)
                    if not data:
                        result["closed"] = True
                        break
                    answer += data
                    result.setdefault("answered_after", sent)
                sock.setblocking(True)
                sock.settimeout(2.0)
        except OSError as exc:  # the server closed the connection (or stopped reading)
            result["send_error"] = repr(exc)
        sock.setblocking(True)
        sock.settimeout(2.0)
        with contextlib.suppress(OSError):
            while True:
                data = sock.recv(65536)
                if not data:
                    result["closed"] = True
                    break
                answer += data
                result.setdefault("answered_after", sent)
    result["sent"] = sent
    result["answer"] = answer


def _measure(process: subprocess.Popen[str], port: int, head: bytes,
             chunk: bytes) -> dict[str, Any]:  # fmt: skip
    time.sleep(0.5)  # let start-up settle
    baseline = _rss_mib(process.pid)
    result: dict[str, Any] = {}
    sender = threading.Thread(target=_stream, args=(port, head, chunk, result), daemon=True)
    sender.start()
    peak = baseline
    while sender.is_alive():
        peak = max(peak, _rss_mib(process.pid))
        time.sleep(0.01)
    sender.join()
    peak = max(peak, _rss_mib(process.pid))
    result.update(baseline=baseline, peak=peak)
    result.setdefault("answered_after", math.inf)
    print(f"RSS {baseline:.1f} -> peak {peak:.1f} MiB; offered {result['sent'] / 2**20:.1f} "
          f"MiB; answer after {result.get('answered_after', 0) / 2**20:.2f} MiB: "
          f"{result['answer'][:40]!r}")  # fmt: skip
    return result


def _head(port: int, framing: str) -> bytes:
    return (f"POST /api/commands/take_photo HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
            f"Content-Type: application/json\r\n{framing}\r\n\r\n").encode()  # fmt: skip


def test_an_endless_chunked_body_is_refused_with_memory_bounded(
    console: tuple[subprocess.Popen[str], int],
) -> None:
    process, port = console
    piece = b" " * 65536
    chunk = b"%x\r\n%s\r\n" % (len(piece), piece)
    result = _measure(process, port, _head(port, "Transfer-Encoding: chunked"), chunk)
    assert result["answer"].startswith(b"HTTP/1.1 413 "), result["answer"][:200]
    assert b"more than 16384 bytes" in result["answer"]
    assert result["answered_after"] < 8 * 2**20, "answered only after megabytes were read"
    assert result["peak"] - result["baseline"] < RSS_GROWTH_MIB, result
    # the connection ends after the answer: the rest of the body is not read (the socket
    # buffers of loopback take a few MiB)
    assert result.get("closed") and result["sent"] < 16 * 2**20, result["sent"]
    assert process.poll() is None  # still serving


def test_a_declared_huge_body_is_refused_before_it_is_read(
    console: tuple[subprocess.Popen[str], int],
) -> None:
    process, port = console
    result = _measure(process, port, _head(port, f"Content-Length: {256 * 2**20}"),
                      b" " * 65536)  # fmt: skip
    assert result["answer"].startswith(b"HTTP/1.1 413 "), result["answer"][:200]
    assert b"268435456 bytes is outside the allowed range [0, 16384] bytes" in result["answer"]
    assert result["peak"] - result["baseline"] < RSS_GROWTH_MIB, result
    assert result.get("closed") and result["sent"] < 16 * 2**20, result["sent"]
    with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=5.0) as http:
        assert http.get("/api/commands").status_code == 200  # still serving


HEADER_TEXT = st.text(st.characters(min_codepoint=0x20, max_codepoint=0x7E), max_size=60).map(
    str.strip
)
"""Printable ASCII, no surrounding space: what an HTTP client can put in a header."""
LOOPBACK_PORTISH = st.sampled_from(["127.0.0.1", "localhost", "[::1]", "LOCALHOST.", "evil"])


@settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(host=HEADER_TEXT | LOOPBACK_PORTISH, origin=st.none() | HEADER_TEXT | st.builds(
    lambda scheme, name, port: f"{scheme}://{name}{port}",
    st.sampled_from(["http", "https", "ws", "file", "null"]), LOOPBACK_PORTISH | HEADER_TEXT,
    st.sampled_from(["", ":80", ":0", ":99999", ":x"]) | st.integers(0, 70000).map(
        lambda p: f":{p}")))  # fmt: skip
def test_hostile_host_and_origin_headers_are_answered_never_500(
    threaded_web: ThreadedWeb, host: str, origin: str | None
) -> None:
    """Whatever ``Host`` and ``Origin`` say, the answer is the guard's 403 or (where both
    are the console's own) the command's own 422 for its bad ratio; never a 500."""
    web = threaded_web.web
    assert web is not None
    headers = {"host": host, "content-type": "application/json"}
    if origin is not None:
        headers["origin"] = origin
    response = threaded_web.http.post("/api/commands/zoom_to", content=b'{"ratio": 0}',
                                      headers=headers)  # fmt: skip
    assert response.status_code in (400, 403, 422), (host, origin, response.text[:300])
    if response.status_code == 403:
        assert response.json()["kind"] in ("ForbiddenHost", "ForbiddenOrigin")
    assert threaded_web.executed == 0
