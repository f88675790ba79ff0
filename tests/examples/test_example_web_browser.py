"""The web example's page in headless Chromium (Debian's /usr/bin/chromium driven by
Playwright; never ``playwright install``): live values and buttons, "Ahead" with an aircraft
heading, the layout at desktop (1280x800) and phone (390x844) widths checked by element
geometry, the stale/disabled state during an outage and its recovery, the error banner
clearing, and a page opened before the GCU is powered. Screenshots go to the test's tmp
directory (``pytest --basetemp=DIR`` keeps them in DIR). Skips, saying what to install,
without the ``web`` extra, Playwright or Chromium.
"""

from __future__ import annotations

import re
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from gcu_async.pytest_plugin import SimHandle
from gcu_async.sim import GcuSimulator
from helpers.examples.web_deps import require_browser

async_api = require_browser()

from helpers.examples.web import (  # noqa: E402
    CHROMIUM,
    CHROMIUM_ARGS,
    Web,
    aircraft_heading,
    free_udp_port,
    running_web,
)

DESKTOP = {"width": 1280, "height": 800}
PHONE = {"width": 390, "height": 844}
WAIT_MS = 5000
"""Bound on every wait for the page (milliseconds)."""
HTTP_ERROR = "the server responded with a status of"
"""Chromium's console line for a fetch answered 4xx/5xx (expected where a test causes one)."""


@pytest.fixture
def web_options() -> dict[str, Any]:
    return {}


@pytest.fixture
async def web(gcu_sim: SimHandle, web_options: dict[str, Any]) -> AsyncIterator[Web]:
    async with running_web(gcu_sim.url, gcu_sim, **web_options) as running:
        yield running


@pytest.fixture
async def browser(tmp_path: Path) -> AsyncIterator[Any]:
    """A Chromium context with a new, empty profile in the test's tmp directory."""
    async with async_api.async_playwright() as pw:
        context = await pw.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=CHROMIUM, args=CHROMIUM_ARGS,
            headless=True, viewport=DESKTOP,
        )  # fmt: skip
        try:
            yield context
        finally:
            await context.close()


class Page:
    """A page of the app with its console errors collected."""

    def __init__(self, page: Any) -> None:
        self.page = page
        self.errors: list[str] = []
        page.on("pageerror", lambda exc: self.errors.append(str(exc)))
        page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)

    async def until(self, expression: str, timeout: int = WAIT_MS) -> None:
        """Wait until a JavaScript expression is true."""
        await self.page.wait_for_function(expression, timeout=timeout)

    async def value(self, expression: str) -> Any:
        return await self.page.evaluate(expression)

    async def text(self, selector: str) -> str:
        return str(await self.page.text_content(selector) or "")

    async def shot(self, path: Path) -> None:
        picture = await self.page.screenshot(path=str(path), full_page=True)
        assert len(picture) > 5000, path  # a real picture, not an empty page

    def unexpected_errors(self) -> list[str]:
        return [e for e in self.errors if HTTP_ERROR not in e]


async def open_page(browser: Any, web: Web, viewport: dict[str, int] = DESKTOP) -> Page:
    page = Page(await browser.new_page())
    await page.page.set_viewport_size(viewport)
    await page.page.goto(web.base_url + "/")
    return page


LIVE = "document.body.dataset.link === 'up'"
BUTTONS = "[...document.querySelectorAll('button[data-command]')]"
ALL_ENABLED = f"{BUTTONS}.every((b) => !b.disabled)"
ALL_DISABLED = f"{BUTTONS}.every((b) => b.disabled)"
STALE = "document.getElementById('live').classList.contains('stale')"


def _rotation(transform: str) -> float:
    match = re.fullmatch(r"rotate\((-?[0-9.]+)\)", transform)
    assert match, transform
    return float(match.group(1))


def yaw_near(value: float, tol: float = 0.5) -> str:
    return (f"Math.abs(((Number(document.getElementById('yaw').textContent) - {value} + 540)"
            f" % 360) - 180) < {tol}")  # fmt: skip


# -- values and buttons -------------------------------------------------------------------
async def test_page_drives_the_gimbal(web: Web, browser: Any, tmp_path: Path) -> None:
    state = web.sim.simulator.model.state
    page = await open_page(browser, web)
    # live values: mode and pod from the simulator, telemetry count rising, buttons on
    await page.until("document.getElementById('mode').textContent === 'POINTING_FOLLOW'")
    assert "D-90Pro(TA)" in await page.text("#pod")
    await page.until("Number(document.getElementById('rx').textContent) > 5")
    await page.until(f"{LIVE} && {ALL_ENABLED} && !({STALE})")
    assert "link up" in await page.text("#link-text")
    assert await page.value("document.getElementById('notice').hidden") is True
    # a button drives the simulator, and the page shows the result
    await page.page.get_by_role("button", name="Photo").click()
    await page.until("document.getElementById('result').textContent.includes('TAKE_PHOTO SUCCESS')")
    assert state.camera.photos == {1: 1}
    # zoom and slew at once (the client queues the two commands)
    await page.page.get_by_role("button", name="10×").click()
    await page.page.get_by_role("button", name="East").click()
    await page.until("Number(document.getElementById('zoom').textContent) >= 9.95")
    assert state.zoom[1] == pytest.approx(10.0, abs=0.05)
    await page.until(f"{yaw_near(90)} && document.getElementById('mode').textContent"
                     " === 'EULER_CONTROL'")  # fmt: skip
    transform = await page.page.get_attribute("#compass-card", "transform") or ""
    assert transform.startswith("rotate(-9")  # the compass card turned to east
    assert page.errors == []  # no script errors, no failed loads (e.g. a favicon)
    # an error shows up on the page too (fill light: the pod lacks it)
    await page.value("send('set_fill_light', {brightness: 10})")
    await page.until("document.getElementById('result').textContent.includes('HTTP 409')")
    assert page.unexpected_errors() == []


async def test_ahead_points_ahead_of_the_aircraft(
    web: Web, browser: Any, tmp_path: Path
) -> None:
    """With the aircraft heading 120°, "Ahead" turns the camera to 120°, not north."""
    state = web.sim.simulator.model.state
    async with aircraft_heading(web.gcu, 120.0):
        page = await open_page(browser, web)
        await page.until(f"{LIVE} && {ALL_ENABLED}")
        await page.until("document.getElementById('aircraft').textContent === '120.0°'")
        await page.page.get_by_role("button", name="West").click()  # somewhere else first
        await page.until(yaw_near(270))
        await page.page.get_by_role("button", name="Ahead", exact=True).click()
        await page.until(f"{yaw_near(120)} && document.getElementById('mode').textContent"
                         " === 'ANGLE_CONTROL'")  # fmt: skip
        await page.until("document.getElementById('result').textContent"
                         ".includes('ANGLE_CONTROL SUCCESS')")  # fmt: skip
        assert abs(state.attitude.yaw - 120.0) < 0.5
        assert abs(state.relative.yaw) < 0.5
        # the compass card turned to 120°, and the aircraft marker on it points at 120°
        card = await page.page.get_attribute("#compass-card", "transform") or ""
        assert abs(_rotation(card) + 120.0) < 0.5, card
        assert await page.page.get_attribute("#aircraft-heading", "transform") == "rotate(120)"
        assert await page.page.get_attribute("#aircraft-heading", "visibility") == "visible"
        await page.shot(tmp_path / "ahead-1280.png")
    assert page.unexpected_errors() == []


# -- layout ------------------------------------------------------------------------------
LAYOUT = """() => {
  const inside = (a, b) => a.left >= b.left - 0.5 && a.right <= b.right + 0.5;
  const box = (el) => el.getBoundingClientRect();
  const out = [];
  const width = document.documentElement.clientWidth;
  if (document.documentElement.scrollWidth > width) {
    out.push(`page scrolls sideways: ${document.documentElement.scrollWidth} > ${width}`);
  }
  for (const el of document.querySelectorAll("body *")) {
    if (el.closest("svg") && el.tagName !== "svg") continue; // clipped drawing inside
    const r = box(el);
    if (r.width === 0 || r.height === 0) continue;
    if (r.left < -0.5 || r.right > width + 0.5) {
      out.push(`${el.tagName}#${el.id}.${el.className.baseVal ?? el.className} outside the `
               + `viewport: ${r.left.toFixed(1)}..${r.right.toFixed(1)} of ${width}`);
    }
  }
  const table = document.querySelector("table.readout");
  const panel = table.closest(".panel");
  const style = getComputedStyle(panel);
  const content = {left: box(panel).left + parseFloat(style.paddingLeft),
                   right: box(panel).right - parseFloat(style.paddingRight)};
  if (!inside(box(table), content)) out.push("the attitude table leaves its panel");
  for (const cell of table.querySelectorAll("th, td")) {
    if (cell.scrollWidth > cell.clientWidth + 0.5) {
      out.push(`cell "${cell.textContent.trim()}" is clipped: ${cell.scrollWidth} > `
               + `${cell.clientWidth}`);
    }
    for (const child of cell.children) {
      if (!inside(box(child), box(cell))) out.push(`"${child.textContent}" leaves its cell`);
    }
  }
  for (const svg of document.querySelectorAll(".instruments svg")) {
    if (!inside(box(svg), content)) out.push(`instrument ${svg.id} leaves its panel`);
    if (box(svg).width < 100) out.push(`instrument ${svg.id} is only ${box(svg).width} px`);
  }
  const panels = [...document.querySelectorAll("main > .panel")].map(box);
  return {problems: out, lefts: panels.map((r) => Math.round(r.left)),
          tops: panels.map((r) => Math.round(r.top))};
}"""


@pytest.mark.parametrize(("name", "viewport"), [("desktop", DESKTOP), ("phone", PHONE)])
async def test_layout_fits_the_screen(
    web: Web, browser: Any, tmp_path: Path, name: str, viewport: dict[str, int]
) -> None:
    page = await open_page(browser, web, viewport)
    await page.until(f"{LIVE} && document.getElementById('pod').textContent.includes('D-90')")
    # wide numbers in every row (pitch −89.00, yaw 181.00, relative Z −179.00)
    response = await web.command("enter_euler_control", {"pitch": -89.0, "yaw": 181.0})
    assert response.status_code == 200
    await page.until(yaw_near(181, 1.0))
    layout = await page.value(LAYOUT)
    await page.shot(tmp_path / f"layout-{name}-{viewport['width']}.png")
    assert layout["problems"] == [], layout["problems"]
    lefts, tops = layout["lefts"], layout["tops"]
    if name == "phone":  # one column: the panels stack
        assert len(set(lefts)) == 1 and tops == sorted(tops) and len(set(tops)) == 3, layout
    else:  # three columns side by side
        assert len(set(tops)) == 1 and lefts == sorted(lefts) and len(set(lefts)) == 3, layout
    assert page.unexpected_errors() == []


# -- outage -------------------------------------------------------------------------------
@pytest.mark.parametrize("web_options", [{"silence_timeout": 0.3}])
async def test_outage_marks_values_stale_and_disables_commands(
    web: Web, browser: Any, tmp_path: Path
) -> None:
    page = await open_page(browser, web, PHONE)
    await page.until(f"{LIVE} && {ALL_ENABLED} && !({STALE})")
    web.sim.silence(60.0)  # the GCU stops answering
    await page.until("document.body.dataset.link === 'down'")
    await page.until(ALL_DISABLED)
    assert await page.value(STALE)
    assert "link DOWN" in await page.text("#link-text")
    notice = await page.text("#notice")
    assert await page.value("!document.getElementById('notice').hidden")
    assert "values below are stale" in notice and "Commands are disabled" in notice
    tag = "getComputedStyle(document.querySelector('.attitude .stale-tag')).display"
    assert await page.value(tag) != "none"
    dimmed = "Number(getComputedStyle(document.querySelector('table.readout')).opacity)"
    assert await page.value(dimmed) < 1
    assert await page.page.get_by_role("button", name="Photo").is_disabled()
    # a command that was on its way when the link went down ends in the error banner
    await page.value("send('take_photo', {})")
    await page.until("document.getElementById('result').textContent.includes('HTTP 503')")
    assert await page.value("document.getElementById('result').className") == "error"
    await page.shot(tmp_path / "outage-390.png")
    await page.page.set_viewport_size(DESKTOP)
    await page.shot(tmp_path / "outage-1280.png")

    web.sim.silence(0)  # replies resume
    await page.until(f"{LIVE} && {ALL_ENABLED} && !({STALE})")
    assert await page.value("document.getElementById('notice').hidden")
    assert await page.value(tag) == "none"
    assert await page.value(dimmed) == 1
    assert "link up" in await page.text("#link-text")
    result = await page.value("document.getElementById('result').className")
    assert result == "idle"  # the outage's error is cleared
    assert await page.text("#result") == "link restored — ready"
    await page.page.get_by_role("button", name="Photo").click()
    await page.until("document.getElementById('result').textContent.includes('TAKE_PHOTO SUCCESS')")
    assert web.sim.simulator.model.state.camera.photos == {1: 1}
    await page.shot(tmp_path / "restored-1280.png")
    assert page.unexpected_errors() == []


async def test_page_waits_for_a_gcu_powered_later(browser: Any, tmp_path: Path) -> None:
    port = free_udp_port()
    url = f"udp://127.0.0.1:{port}"
    options: dict[str, Any] = {"connect_timeout": 0.3}
    async with running_web(url, None, wait_connected=False, **options) as web:
        page = await open_page(browser, web, PHONE)
        await page.until("document.body.dataset.link === 'waiting'")
        await page.until("document.getElementById('link-text').textContent.includes('attempt')")
        assert await page.value(ALL_DISABLED)
        assert await page.value(STALE)
        notice = await page.text("#notice")
        assert f"Waiting for the GCU at {url}" in notice
        assert "no reply from the GCU" in notice
        assert await page.text("#mode") == "—"  # nothing received, nothing made up
        await page.shot(tmp_path / "waiting-390.png")
        sim = GcuSimulator()
        async with sim.serve_udp("127.0.0.1", port):  # the GCU is powered on
            await page.until(f"{LIVE} && {ALL_ENABLED} && !({STALE})")
            await page.until("document.getElementById('mode').textContent === 'POINTING_FOLLOW'")
            assert await page.value("document.getElementById('notice').hidden")
            await page.page.get_by_role("button", name="Photo").click()
            await page.until(
                "document.getElementById('result').textContent.includes('TAKE_PHOTO SUCCESS')"
            )
            assert sim.model.state.camera.photos == {1: 1}
            await page.shot(tmp_path / "connected-390.png")
        assert page.unexpected_errors() == []
