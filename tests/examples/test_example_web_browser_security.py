"""The web console against hostile pages, in real Chromium (Debian's /usr/bin/chromium
driven by Playwright): a page served from another origin (a second loopback server, on
127.0.0.2) tries a simple ``fetch``, a preflighted one, two form POSTs, a cross-origin read
and WebSockets; a name rebound to 127.0.0.1 (``--host-resolver-rules``, as DNS rebinding
would) loads the console's URL. The simulated GCU, which counts every command it executes,
must execute none of it, and the console's own log must show the requests arrived and
were refused (not merely lost on the way). The console from its own origin, with and
without a token, still drives the gimbal. Skips, saying what to install, without the
``web`` extra, Playwright or Chromium.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from gcu_async.pytest_plugin import SimHandle
from helpers.examples.web_deps import require_browser

async_api = require_browser()

from starlette.applications import Starlette  # noqa: E402
from starlette.responses import HTMLResponse  # noqa: E402
from starlette.routing import Route  # noqa: E402

from helpers.examples.web import CHROMIUM, CHROMIUM_ARGS, Web, running_web, serve  # noqa: E402

WAIT_MS = 10_000
REBOUND = "rebind.example"
"""A foreign name Chromium resolves to 127.0.0.1, as a DNS rebinding attack makes it."""
TOKEN = "browser-token-0123456789abcdef"
LIVE = "document.body.dataset.link === 'up'"
BUTTONS = "[...document.querySelectorAll('button[data-command]')]"
ALL_ENABLED = f"{BUTTONS}.every((b) => !b.disabled)"
PHOTO_OK = "document.getElementById('result').textContent.includes('TAKE_PHOTO SUCCESS')"


@pytest.fixture
def web_options() -> dict[str, Any]:
    return {}


@pytest.fixture
async def web(gcu_sim: SimHandle, web_options: dict[str, Any],
              caplog: pytest.LogCaptureFixture) -> AsyncIterator[Web]:  # fmt: skip
    caplog.set_level(logging.INFO, logger="gcu_async.examples.web")
    async with running_web(gcu_sim.url, gcu_sim, **web_options) as running:
        yield running


@contextlib.asynccontextmanager
async def chromium(tmp_path: Path, *extra: str) -> AsyncIterator[Any]:
    """A Chromium context with a new, empty profile in the test's tmp directory."""
    async with async_api.async_playwright() as pw:
        context = await pw.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=CHROMIUM, args=[*CHROMIUM_ARGS, *extra],
            headless=True,
        )  # fmt: skip
        try:
            yield context
        finally:
            await context.close()


def executed(web: Web) -> int:
    return sum(web.sim.simulator.model.executions.values())


def refusals(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.getMessage().startswith("refused ")]


ATTACK = """<!doctype html><meta charset="utf-8"><title>a page elsewhere</title>
<iframe name="sink1"></iframe><iframe name="sink2"></iframe>
<form id="photo" method="post" action="CONSOLE/api/commands/take_photo" target="sink1"></form>
<form id="zoom" method="post" enctype="text/plain" action="CONSOLE/api/commands/zoom_to"
      target="sink2"><input name='{"ratio": 30, "x": "' value='"}'></form>
<script>
"use strict";
const target = "CONSOLE";
const wsTarget = target.replace("http://", "ws://") + "/ws/telemetry";
window.results = {};
function socket(protocols) {
  return new Promise((resolve) => {
    let messages = 0;
    const ws = protocols ? new WebSocket(wsTarget, protocols) : new WebSocket(wsTarget);
    ws.onmessage = () => { messages += 1; };
    ws.onopen = () => setTimeout(() => { resolve(`open, ${messages} messages`); ws.close(); },
                                 1500);
    ws.onerror = () => resolve("error");
  });
}
function submitted(form, frame) {
  return new Promise((resolve) => {
    document.querySelector(`iframe[name=${frame}]`).onload = () => resolve("loaded");
    document.getElementById(form).submit();
    setTimeout(() => resolve("no load event"), 3000);
  });
}
async function attack() {
  try {  // a "simple" request: no preflight, the answer is opaque but it is sent
    await fetch(`${target}/api/commands/zoom_to`, {method: "POST", mode: "no-cors",
      headers: {"Content-Type": "text/plain"}, body: '{"ratio": 10}'});
    results.simple = "sent";
  } catch (error) { results.simple = `error ${error}`; }
  try {  // JSON: Chromium asks first (OPTIONS); the console grants no CORS
    const response = await fetch(`${target}/api/commands/zoom_to`, {method: "POST",
      headers: {"Content-Type": "application/json"}, body: '{"ratio": 20}'});
    results.preflighted = `status ${response.status}`;
  } catch (error) { results.preflighted = `blocked ${error}`; }
  try {
    const response = await fetch(`${target}/api/status`);
    results.read = await response.text();
  } catch (error) { results.read = `blocked ${error}`; }
  results.form = await submitted("photo", "sink1");
  results.textForm = await submitted("zoom", "sink2");
  results.socket = await socket();
  results.socketWithProtocol = await socket(["gcu-async.telemetry"]);
  results.done = true;
}
attack();
</script>"""


@contextlib.asynccontextmanager
async def attacker_site(console: str) -> AsyncIterator[str]:
    """A page on another origin (127.0.0.2, its own port) aimed at ``console``."""
    html = ATTACK.replace("CONSOLE", console)

    async def page(request: Any) -> HTMLResponse:
        return HTMLResponse(html)

    async with serve(Starlette(routes=[Route("/", page)]), host="127.0.0.2") as url:
        yield url


async def test_a_page_from_another_origin_cannot_reach_the_gimbal(
    web: Web, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    state = web.sim.simulator.model.state
    zoom = state.zoom[1]
    async with attacker_site(web.base_url) as evil, chromium(tmp_path) as browser:
        page = await browser.new_page()
        await page.goto(evil + "/")
        await page.wait_for_function("window.results.done === true", timeout=WAIT_MS)
        results = await page.evaluate("window.results")
        await page.screenshot(path=str(tmp_path / "attacker.png"))
    # nothing executed: no zoom, no photo (the simulator's own count)
    assert executed(web) == 0, (web.sim.simulator.model.executions, results)
    assert state.zoom[1] == zoom and state.camera.photos == {}
    # what the page saw: the preflighted POST and the read blocked, the sockets refused
    assert results["simple"] == "sent", results
    assert results["preflighted"].startswith("blocked"), results
    assert results["read"].startswith("blocked"), results
    assert results["socket"] == "error" and results["socketWithProtocol"] == "error", results
    # what the console saw: the requests that got through the browser, each refused
    seen = refusals(caplog)
    for line in ("refused POST /api/commands/zoom_to: Origin 'http://127.0.0.2:",
                 "refused POST /api/commands/take_photo: Origin 'http://127.0.0.2:",
                 "refused WEBSOCKET /ws/telemetry: Origin 'http://127.0.0.2:"):  # fmt: skip
        assert any(s.startswith(line) for s in seen), (line, seen)
    assert sum("zoom_to" in s for s in seen) == 2  # the simple fetch and the text/plain form
    assert sum("/ws/telemetry" in s for s in seen) == 2


async def test_dns_rebinding_is_refused(
    web: Web, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    port = web.base_url.rsplit(":", 1)[1]
    rules = f"--host-resolver-rules=MAP {REBOUND} 127.0.0.1"
    async with chromium(tmp_path, rules) as browser:
        page = await browser.new_page()
        response = await page.goto(f"http://{REBOUND}:{port}/")
        assert response is not None and response.status == 403
        assert "ForbiddenHost" in await page.content()
        # the page the attacker controls is now same-origin with the rebound name
        results = await page.evaluate("""async () => {
          const post = await fetch("/api/commands/take_photo", {method: "POST",
            headers: {"Content-Type": "application/json"}, body: "{}"});
          const read = await fetch("/api/status");
          const socket = await new Promise((resolve) => {
            const ws = new WebSocket(`ws://${location.host}/ws/telemetry`);
            ws.onopen = () => { resolve("open"); ws.close(); };
            ws.onerror = () => resolve("error");
          });
          return {post: post.status, read: read.status, body: await read.text(), socket};
        }""")
    assert (results["post"], results["read"], results["socket"]) == (403, 403, "error"), results
    assert "attitude" not in results["body"]
    assert executed(web) == 0
    seen = refusals(caplog)
    assert any(f"Host '{REBOUND}:{port}' is not allowed" in s for s in seen), seen
    assert any(s.startswith("refused WEBSOCKET /ws/telemetry: Host") for s in seen), seen


@pytest.mark.parametrize("name", ["127.0.0.1", "localhost"])
async def test_the_console_still_works_from_its_own_origin(
    web: Web, tmp_path: Path, name: str
) -> None:
    port = web.base_url.rsplit(":", 1)[1]
    async with chromium(tmp_path) as browser:
        page = await browser.new_page()
        await page.goto(f"http://{name}:{port}/")
        await page.wait_for_function(f"{LIVE} && {ALL_ENABLED}", timeout=WAIT_MS)
        await page.get_by_role("button", name="Photo").click()
        await page.wait_for_function(PHOTO_OK, timeout=WAIT_MS)
        await page.get_by_role("button", name="10×").click()
        await page.wait_for_function(
            "Number(document.getElementById('zoom').textContent) >= 9.95", timeout=WAIT_MS)
    assert web.sim.simulator.model.state.camera.photos == {1: 1}


@pytest.mark.parametrize("web_options", [{"token": TOKEN}])
async def test_the_console_with_a_token(web: Web, tmp_path: Path) -> None:
    """Opened as /#token=…: live telemetry (the token as a WebSocket subprotocol) and
    commands (as a header); the token leaves the address bar. Opened without it: the page
    says so, and nothing runs."""
    async with chromium(tmp_path) as browser:
        page = await browser.new_page()
        await page.goto(f"{web.base_url}/")
        await page.wait_for_function(
            "document.getElementById('link-text').textContent.includes('needs its token')",
            timeout=WAIT_MS)  # fmt: skip
        assert await page.evaluate(f"{BUTTONS}.every((b) => b.disabled)")

        page = await browser.new_page()
        await page.goto(f"{web.base_url}/#token={TOKEN}")
        await page.wait_for_function(f"{LIVE} && {ALL_ENABLED}", timeout=WAIT_MS)
        assert TOKEN not in page.url
        await page.get_by_role("button", name="Photo").click()
        await page.wait_for_function(PHOTO_OK, timeout=WAIT_MS)
        await page.reload()  # the tab keeps it (sessionStorage)
        await page.wait_for_function(f"{LIVE} && {ALL_ENABLED}", timeout=WAIT_MS)
        await page.screenshot(path=str(tmp_path / "token.png"))
    assert web.sim.simulator.model.state.camera.photos == {1: 1}
