"""The web example's protections over HTTP (httpx) and WebSocket (websockets), against the
real app under uvicorn on 127.0.0.1 and the simulator, which counts every command it
executes: every refused request must leave that count at zero. The browser's view of the
same rules is tests/examples/test_example_web_browser_security.py; hostile bodies by hypothesis and
the body limit's memory bound are tests/examples/test_example_web_bodies.py.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from typing import Any

import pytest

from gcu_async.pytest_plugin import SimHandle
from helpers.examples.web_deps import require_web

require_web()
from websockets.asyncio.client import connect as ws_connect  # noqa: E402
from websockets.exceptions import InvalidStatus  # noqa: E402
from websockets.typing import Origin, Subprotocol  # noqa: E402

from helpers.examples.web import Web, next_message, running_web  # noqa: E402

TOKEN = "test-token-0123456789abcdef"
JSON = {"content-type": "application/json"}


@pytest.fixture
def web_options() -> dict[str, Any]:
    return {}


@pytest.fixture
async def web(gcu_sim: SimHandle, web_options: dict[str, Any]) -> AsyncIterator[Web]:
    async with running_web(gcu_sim.url, gcu_sim, **web_options) as running:
        yield running


def executed(web: Web) -> int:
    """Commands the simulated GCU has executed so far."""
    return sum(web.sim.simulator.model.executions.values())


def own_origin(web: Web) -> str:
    return web.base_url


async def post(web: Web, name: str, body: bytes, **headers: str) -> Any:
    return await web.http.post(f"/api/commands/{name}", content=body, headers=headers)


# -- state-changing requests from other origins ---------------------------------------------
async def test_cross_origin_text_plain_post_does_not_zoom(web: Web) -> None:
    """The finding: a page's ``fetch(..., {mode: "no-cors", body, text/plain})`` ran zoom_to."""
    response = await post(web, "zoom_to", b'{"ratio": 10}', **{
        "content-type": "text/plain;charset=UTF-8", "origin": "http://evil.example",
        "sec-fetch-site": "cross-site"})  # fmt: skip
    assert response.status_code == 403
    assert response.json()["kind"] == "ForbiddenOrigin"
    assert "http://evil.example" in response.json()["error"]
    assert executed(web) == 0


async def test_cross_origin_form_post_without_body_takes_no_photo(web: Web) -> None:
    response = await post(web, "take_photo", b"", **{
        "content-type": "application/x-www-form-urlencoded", "origin": "http://evil.example"})
    assert response.status_code == 403
    assert executed(web) == 0
    assert web.sim.simulator.model.state.camera.photos == {}


@pytest.mark.parametrize("origin", [
    "null", "http://evil.example", "http://127.0.0.2:{port}", "http://127.0.0.1:1",
    "http://127.0.0.1", "file://", "chrome-extension://abc", "http://127.0.0.1:{port}/x",
    "http://user@127.0.0.1:{port}", "http://localhost:{port}", "garbage",
])  # fmt: skip
async def test_foreign_origins_are_refused(web: Web, origin: str) -> None:
    port = web.base_url.rsplit(":", 1)[1]
    origin = origin.format(port=port)
    response = await post(web, "take_photo", b"{}", **JSON, origin=origin)
    assert response.status_code == 403, (origin, response.text)
    assert response.json()["kind"] == "ForbiddenOrigin"
    assert executed(web) == 0


async def test_same_origin_and_originless_posts_run(web: Web) -> None:
    """The page's own origin (http or https, same host and port) and a client that sends no
    Origin at all (curl, a script) are served."""
    port = web.base_url.rsplit(":", 1)[1]
    for headers in ({"origin": own_origin(web)}, {"origin": f"https://127.0.0.1:{port}"}, {},
                    {"sec-fetch-site": "same-origin", "origin": own_origin(web)},
                    {"sec-fetch-site": "none"}):  # fmt: skip
        response = await post(web, "take_photo", b"{}", **JSON, **headers)
        assert response.status_code == 200, (headers, response.text)
    assert web.sim.simulator.model.state.camera.photos == {1: 5}


async def test_originless_cross_site_fetch_metadata_is_refused(web: Web) -> None:
    response = await post(web, "take_photo", b"{}", **JSON, **{"sec-fetch-site": "cross-site"})
    assert response.status_code == 403
    assert executed(web) == 0


async def test_json_bodies_only_as_json(web: Web) -> None:
    """Without an Origin (so the Origin rule does not decide) a body not declared JSON is
    415: text/plain and forms are what a browser may send anywhere without a preflight."""
    for content_type in ("text/plain", "application/x-www-form-urlencoded",
                         "multipart/form-data; boundary=x", "application/json; charset=latin-1",
                         "application/jsonx", ""):  # fmt: skip
        headers = {"content-type": content_type} if content_type else {}
        response = await post(web, "zoom_to", b'{"ratio": 10}', **headers)
        assert response.status_code == 415, (content_type, response.text)
        assert "application/json" in response.json()["error"]
    for content_type in ("application/json", "Application/JSON; charset=UTF-8"):
        response = await post(web, "zoom_to", b'{"ratio": 2}', **{"content-type": content_type})
        assert response.status_code == 200, (content_type, response.text)
    assert executed(web) == 2


# -- WebSocket ------------------------------------------------------------------------------
@pytest.mark.parametrize("origin", ["http://evil.example", "null", "http://127.0.0.2:8000"])
async def test_websocket_from_a_foreign_origin_is_refused(web: Web, origin: str) -> None:
    with pytest.raises(InvalidStatus) as caught:
        async with ws_connect(web.ws_url, origin=Origin(origin), open_timeout=5):
            pass
    assert caught.value.response.status_code == 403


async def test_websocket_from_its_own_page_streams(web: Web) -> None:
    async with ws_connect(web.ws_url, origin=Origin(own_origin(web))) as ws:
        assert (await next_message(ws))["type"] in ("telemetry", "link")
    async with ws_connect(web.ws_url, subprotocols=[Subprotocol("gcu-async.telemetry")]) as ws:
        assert ws.subprotocol == "gcu-async.telemetry"
        assert (await next_message(ws))["type"] in ("telemetry", "link")


# -- DNS rebinding: the Host header --------------------------------------------------------
@pytest.mark.parametrize("host", ["attacker.example", "attacker.example:{port}",
                                  "127.0.0.1.attacker.example", "localhost.attacker.example",
                                  "127.0.0.2:{port}", "[::2]:{port}", "", "a b"])  # fmt: skip
async def test_foreign_host_is_refused(web: Web, host: str) -> None:
    port = web.base_url.rsplit(":", 1)[1]
    host = host.format(port=port)
    paths = (("GET", "/"), ("GET", "/api/status"), ("POST", "/api/commands/take_photo"))
    for method, path in paths:
        response = await web.http.request(method, path, headers={"host": host, **JSON},
                                          content=b"{}")  # fmt: skip
        assert response.status_code == 403, (host, path, response.text)
        assert response.json()["kind"] == "ForbiddenHost"
    if host.strip() and " " not in host:  # a name a browser could have resolved (rebinding)
        url = f"ws://{host}/ws/telemetry" if ":" in host else f"ws://{host}:{port}/ws/telemetry"
        with pytest.raises(InvalidStatus) as caught:  # the URL's name, our socket
            async with ws_connect(url, host="127.0.0.1", port=int(port), open_timeout=5):
                pass
        assert caught.value.response.status_code == 403
    assert executed(web) == 0


async def test_loopback_names_are_served(web: Web) -> None:
    port = web.base_url.rsplit(":", 1)[1]
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"LOCALHOST.:{port}", "127.0.0.1",
                 f"[::1]:{port}"):  # fmt: skip
        response = await web.http.get("/api/status", headers={"host": host})
        assert response.status_code == 200, (host, response.text)


@pytest.mark.parametrize("web_options", [{"allowed_hosts": ["gimbal.lan", "127.0.0.1"]}])
async def test_allowed_hosts_replace_the_default(web: Web) -> None:
    assert (await web.http.get("/", headers={"host": "gimbal.lan:8000"})).status_code == 200
    assert (await web.http.get("/", headers={"host": "localhost"})).status_code == 403
    # behind a TLS proxy: Host without a port, the page's origin https on 443
    for origin, status in (("https://gimbal.lan", 200), ("https://gimbal.lan:443", 200),
                           ("http://gimbal.lan", 200), ("https://gimbal.lan:8443", 403),
                           ("https://evil.lan", 403)):  # fmt: skip
        response = await post(web, "take_photo", b"{}", **JSON, host="gimbal.lan", origin=origin)
        assert response.status_code == status, (origin, response.text)
    assert executed(web) == 3


# -- the bearer token ------------------------------------------------------------------------
@pytest.mark.parametrize("web_options", [{"token": TOKEN}])
async def test_token_is_needed_for_the_api_and_the_socket(web: Web) -> None:
    # the page and its files hold no secret: served without the token
    assert (await web.http.get("/")).status_code == 200
    assert (await web.http.get("/static/app.js")).status_code == 200
    for auth in ({}, {"authorization": "Bearer wrong-token-0123456789"},
                 {"authorization": f"Basic {TOKEN}"}, {"authorization": TOKEN},
                 {"authorization": f"Bearer {TOKEN}x"}):  # fmt: skip
        for method, path in (("GET", "/api/status"), ("GET", "/api/commands"),
                             ("POST", "/api/commands/take_photo")):  # fmt: skip
            response = await web.http.request(method, path, headers={**auth, **JSON},
                                              content=b"{}")  # fmt: skip
            assert response.status_code == 401, (auth, path, response.text)
            assert response.headers["www-authenticate"] == "Bearer"
            assert TOKEN not in response.text
    for protocols in (None, ["gcu-async.telemetry"], ["gcu-async.telemetry", "gcu-async.bearer.x"]):
        offered = None if protocols is None else [Subprotocol(p) for p in protocols]
        with pytest.raises(InvalidStatus) as caught:
            async with ws_connect(web.ws_url, subprotocols=offered, open_timeout=5):
                pass
        assert caught.value.response.status_code == 403
    assert executed(web) == 0
    # with the token: the API by header, the socket by header or (as a browser) subprotocol
    bearer = {"authorization": f"Bearer {TOKEN}"}
    assert (await web.http.get("/api/status", headers=bearer)).status_code == 200
    response = await post(web, "take_photo", b"{}", **JSON, **bearer)
    assert response.status_code == 200, response.text
    assert web.sim.simulator.model.state.camera.photos == {1: 1}
    async with ws_connect(web.ws_url, additional_headers=bearer) as ws:
        assert (await next_message(ws))["type"] in ("telemetry", "link")
    offer = [Subprotocol("gcu-async.telemetry"), Subprotocol(f"gcu-async.bearer.{TOKEN}")]
    async with ws_connect(web.ws_url, subprotocols=offer,
                          origin=Origin(own_origin(web))) as ws:  # fmt: skip
        assert ws.subprotocol == "gcu-async.telemetry"  # never the token echoed back
        assert (await next_message(ws))["type"] in ("telemetry", "link")


@pytest.mark.parametrize("web_options", [{"token": TOKEN}])
async def test_token_does_not_replace_the_origin_check(web: Web) -> None:
    bearer = {"authorization": f"Bearer {TOKEN}"}
    response = await post(web, "take_photo", b"{}", **JSON, **bearer, origin="http://evil.example")
    assert response.status_code == 403
    assert executed(web) == 0


@pytest.mark.parametrize("token", ["short", "x" * 257, "has space in it 0123", "ünïcödé-0123456789",
                                   "comma,is,not,allowed,0123"])  # fmt: skip
def test_a_bad_token_is_refused_at_once(token: str) -> None:
    from examples.web.app import create_app

    with pytest.raises(ValueError, match=r"token: expected 16 to 256 characters") as caught:
        create_app("udp://127.0.0.1:2337", local_port=0, token=token)
    assert token not in str(caught.value)  # the secret is not echoed


@pytest.mark.parametrize("hosts", [["127.0.0.1:8000"], [""], ["http://x"], ["a@b"]])
def test_a_bad_allowed_host_is_refused_at_once(hosts: list[str]) -> None:
    from examples.web.app import create_app

    with pytest.raises(ValueError, match="allowed host"):
        create_app("udp://127.0.0.1:2337", local_port=0, allowed_hosts=hosts)


# -- bodies ---------------------------------------------------------------------------------
async def test_a_400_digit_integer_is_422_naming_field_range_and_value(web: Web) -> None:
    """The finding: ``{"ratio": <400 digits>}`` was an OverflowError, HTTP 500."""
    huge = "9" * 400
    response = await post(web, "zoom_to", f'{{"ratio": {huge}}}'.encode(), **JSON)
    assert response.status_code == 422, response.text
    body = response.json()
    assert body["kind"] == "FieldRangeError" and body["field"] == "ratio"
    assert (body["low"], body["high"]) == (1.0, pytest.approx(3276.8))
    assert body["error"].startswith(f"ratio: {huge} is outside the allowed range [1, 3276.8]")
    for name, key in (("take_photo", "cameras"), ("set_fill_light", "brightness"),
                      ("set_night_vision", "mode"), ("enter_euler_control", "yaw")):  # fmt: skip
        response = await post(web, name, f'{{"{key}": -{huge}}}'.encode(), **JSON)
        assert response.status_code == 422, (name, response.text)
        assert response.json()["error"].startswith(f"{key}: -{huge} is outside"), response.text
    response = await post(web, "track", f'{{"box": [0, 0, {huge}, 1]}}'.encode(), **JSON)
    assert response.status_code == 422 and "box[2]" in response.json()["error"], response.text
    response = await post(web, "calibrate", f'{{"timeout": {huge}}}'.encode(), **JSON)
    assert response.status_code == 422 and "timeout: an integer of 400 digits" in response.text
    assert executed(web) == 0


async def test_deep_nesting_is_400_not_500(web: Web) -> None:
    for body in ("[" * 100_000, '{"a":' * 5000 + "1" + "}" * 5000, "[" * 9 + "]" * 9):
        response = await post(web, "take_photo", body.encode()[:16000], **JSON)
        assert response.status_code == 400, response.text
        assert "nesting depth" in response.json()["error"]
        assert "outside the allowed range [0, 8]" in response.json()["error"]
    assert executed(web) == 0


async def test_bodies_that_are_not_clean_json_are_400(web: Web) -> None:
    cases = {
        b'{"ratio": 2, "ratio": 3000}': "duplicate key 'ratio'",
        b"\xff\xfe{}": "not UTF-8",
        b'{"ratio": 1' + b"1" * 5000 + b"}": "not valid JSON",  # past Python's int digit limit
        b"{not json": "not valid JSON",
    }
    for raw, message in cases.items():
        response = await post(web, "zoom_to", raw, **JSON)
        assert response.status_code == 400, (raw[:40], response.text)
        assert message in response.json()["error"], response.text
    assert executed(web) == 0


async def test_a_body_over_the_limit_is_413(web: Web) -> None:
    body = json.dumps({"ratio": 2, "pad": "x" * 20_000}).encode()
    response = await post(web, "zoom_to", body, **JSON)
    assert response.status_code == 413, response.text
    assert "allowed range [0, 16384] bytes" in response.json()["error"]

    # no Content-Length (chunked): counted as it is read; one byte over is refused
    port = int(web.base_url.rsplit(":", 1)[1])
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    pieces = [b" " * 4096] * 4 + [b"{}"]
    body = b"".join(b"%x\r\n%s\r\n" % (len(p), p) for p in pieces) + b"0\r\n\r\n"
    writer.write(b"POST /api/commands/take_photo HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                 b"Content-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n" + body)
    answer = await asyncio.wait_for(reader.read(), 5.0)  # to the end: the server closes
    writer.close()
    assert answer.startswith(b"HTTP/1.1 413 "), answer
    assert b"connection: close" in answer.lower()
    assert b"more than 16384 bytes" in answer
    assert executed(web) == 0


@pytest.mark.parametrize("web_options", [{"max_body": 64}])
async def test_the_body_limit_is_configurable(web: Web) -> None:
    response = await post(web, "take_photo", b" " * 65 + b"{}", **JSON)
    assert response.status_code == 413
    response = await post(web, "take_photo", b" " * 40 + b"{}", **JSON)
    assert response.status_code == 200


@pytest.mark.parametrize("max_body", [0, 1, 2**20 + 1, 1.5, True, "16"])
def test_a_bad_body_limit_is_refused_at_once(max_body: Any) -> None:
    from examples.web.app import create_app

    message = r"max_body: .* is outside the allowed range \[2, 1048576\]"
    with pytest.raises(ValueError, match=message):
        create_app("udp://127.0.0.1:2337", local_port=0, max_body=max_body)


async def test_a_null_body_is_not_an_empty_one(web: Web) -> None:
    """JSON ``null`` used to read as "no body": every default, executed."""
    for name in ("take_photo", "enter_euler_control", "centre"):
        response = await post(web, name, b"null", **JSON)
        assert response.status_code == 422, (name, response.text)
        assert "the body must be a JSON object, got null" in response.json()["error"]
    assert executed(web) == 0
