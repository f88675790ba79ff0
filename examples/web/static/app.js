// gcu_async web example: live telemetry over a WebSocket, commands over JSON POST.
"use strict";

const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";
const PX_PER_DEG = 1.4; // horizon pitch scale
// The bearer token, when the server wants one: opened as /#token=..., kept for this tab
// (sessionStorage) and taken out of the address bar, so it is not shared with the URL.
const TOKEN = (() => {
  const match = /(?:^#|&)token=([A-Za-z0-9._~-]+)/.exec(location.hash);
  if (match) {
    sessionStorage.setItem("gcu-token", match[1]);
    history.replaceState(null, "", location.pathname + location.search);
  }
  return sessionStorage.getItem("gcu-token");
})();
const AUTH = TOKEN ? { Authorization: `Bearer ${TOKEN}` } : {};
// A browser cannot set headers on a WebSocket: the token travels as a subprotocol, beside
// the one the server accepts (it never echoes the token back).
const WS_PROTOCOLS = TOKEN ? ["gcu-async.telemetry", `gcu-async.bearer.${TOKEN}`]
  : ["gcu-async.telemetry"];
const fmt = (v, digits = 2) => (v === null || v === undefined ? "—" : v.toFixed(digits));

function svg(parent, tag, attrs, text) {
  const el = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, v);
  if (text !== undefined) el.textContent = text;
  parent.appendChild(el);
  return el;
}

function drawInstruments() {
  const ladder = $("pitch-ladder");
  ladder.setAttribute("class", "ladder");
  for (let p = -90; p <= 90; p += 10) {
    if (p === 0) continue;
    const y = -p * PX_PER_DEG;
    const half = p % 30 === 0 ? 28 : 14;
    svg(ladder, "line", { x1: -half, x2: half, y1: y, y2: y });
    if (p % 30 === 0) svg(ladder, "text", { x: half + 4, y }, String(p));
  }
  const card = $("compass-card");
  for (let d = 0; d < 360; d += 10) {
    const major = d % 30 === 0;
    svg(card, "line", {
      x1: 0, x2: 0, y1: -90, y2: major ? -78 : -84,
      class: major ? "tick major" : "tick", transform: `rotate(${d})`,
    });
  }
  for (const [d, label] of [[0, "N"], [90, "E"], [180, "S"], [270, "W"]]) {
    const t = svg(card, "text", { x: 0, y: -66, class: "card-label" }, label);
    if (label === "N") t.classList.add("north");
    t.setAttribute("transform", `rotate(${d})`);
  }
}

// -- link state: up (live values, commands enabled) or not (stale values, commands off) --
// view: "connecting" (page loading), "waiting" (the app's client is not open: no GCU yet,
// or the client failed), "down" (the client is open but no replies arrive), "up",
// "offline" (no telemetry socket).
let view = "connecting";
let lastTelemetry = null; // performance.now() of the last telemetry message

function ago(seconds) {
  if (seconds === null || seconds === undefined) return "no reply yet";
  return seconds < 60 ? `${seconds.toFixed(1)} s ago` : `${Math.round(seconds / 60)} min ago`;
}

function lastUpdate() {
  if (lastTelemetry === null) return "no values received yet";
  return `last values ${ago((performance.now() - lastTelemetry) / 1000)}`;
}

function linkText(next, link, connection, note) {
  if (note) return note;
  if (next === "up") return `link up · ${link.reply_rate.toFixed(0)} replies/s`;
  if (next === "down") return `link DOWN — no reply ${ago(link ? link.last_reply_age : null)}`;
  if (next === "waiting") {
    if (connection.state === "failed") return "client failed";
    const tries = connection.attempts ? ` · attempt ${connection.attempts + 1}` : "";
    return `waiting for the GCU${tries}`;
  }
  return "connecting…";
}

function noticeText(next, connection) {
  if (next === "waiting") {
    let text = `Waiting for the GCU at ${connection.url}: it has not answered yet`;
    if (connection.state === "failed") {
      text = `The client of the GCU at ${connection.url} stopped: ${connection.last_error}`;
    } else if (connection.last_error) {
      text += ` (${connection.last_error})`;
    }
    return `${text}. Commands are disabled; ${lastUpdate()}.`;
  }
  if (next === "down") {
    return `Link to the GCU lost: the values below are stale (${lastUpdate()}). `
      + "Commands are disabled until replies return.";
  }
  if (next === "offline") {
    return `No connection to this server: the values below are stale (${lastUpdate()}).`;
  }
  return "";
}

// Apply a link view. `link` and `connection` come from the server (null when unknown).
function setView(next, link = null, connection = null, note = "") {
  const previous = view;
  view = next;
  const up = next === "up";
  document.body.dataset.link = next;
  $("link").className = `link ${up ? "up" : next}`;
  $("link-text").textContent = linkText(next, link, connection, note);
  $("live").classList.toggle("stale", !up);
  for (const tag of document.querySelectorAll(".stale-tag")) {
    tag.textContent = lastTelemetry === null ? "no data" : "stale";
  }
  const notice = $("notice");
  notice.textContent = noticeText(next, connection);
  notice.hidden = up || next === "connecting";
  for (const button of document.querySelectorAll("button[data-command]")) {
    button.disabled = !up;
  }
  if (up && previous !== "up") {
    // the link is back: an error from the outage no longer describes the gimbal
    const out = $("result");
    if (out.className === "error") {
      out.className = "idle";
      out.textContent = previous === "connecting" ? "ready" : "link restored — ready";
    }
  }
}

// A server message's link state: the client must be open and its link up.
function applyLink(link, connection) {
  if (connection && connection.state !== "open") setView("waiting", link, connection);
  else if (link && link.up) setView("up", link, connection);
  else setView("down", link, connection);
}

function render(s) {
  const a = s.attitude;
  $("roll").textContent = fmt(a.roll);
  $("pitch").textContent = fmt(a.pitch);
  $("yaw").textContent = fmt(a.yaw);
  $("rel-x").textContent = fmt(s.relative.x);
  $("rel-y").textContent = fmt(s.relative.y);
  $("rel-z").textContent = fmt(s.relative.z);
  $("rate-x").textContent = fmt(s.rates.x, 1);
  $("rate-y").textContent = fmt(s.rates.y, 1);
  $("rate-z").textContent = fmt(s.rates.z, 1);
  $("horizon-ball").setAttribute(
    "transform", `rotate(${-a.roll}) translate(0 ${a.pitch * PX_PER_DEG})`);
  $("compass-card").setAttribute("transform", `rotate(${-a.yaw})`);
  $("compass-value").textContent = `${a.yaw.toFixed(0)}°`;
  $("mode").textContent = s.mode;
  $("tracking").textContent = s.tracking ? "target locked" : "no";
  if (s.zoom) {
    $("zoom").textContent = fmt(s.zoom.camera1, 1);
    $("zoom2").textContent = `${fmt(s.zoom.camera2, 1)}×`;
  }
  const rec = $("recording");
  rec.textContent = s.recording ? "● REC" : "no";
  rec.className = s.recording ? "on" : "";
  const button = $("record-button");
  button.textContent = s.recording ? "Stop recording" : "Record";
  button.classList.toggle("recording", Boolean(s.recording));
  $("distance").textContent =
    s.target_distance_m === null ? "—" : `${s.target_distance_m.toFixed(1)} m`;
  const flags = [...s.pod_status];
  if (s.flags) flags.push(...s.flags.camera, ...s.flags.thermal, ...s.flags.faults);
  $("flags").textContent = flags.length ? flags.join(", ") : "none";
  if (s.pod) {
    $("pod").textContent =
      `${s.pod.model} · hw ${s.pod.hardware_version} · fw ${s.pod.firmware_version}`;
  }
  const heading = s.aircraft_heading;
  $("aircraft").textContent = heading === null ? "not sent" : `${heading.toFixed(1)}°`;
  const marker = $("aircraft-heading");
  marker.setAttribute("visibility", heading === null ? "hidden" : "visible");
  if (heading !== null) marker.setAttribute("transform", `rotate(${heading})`);
}

const arrivals = [];
function countMessage() {
  const now = performance.now();
  arrivals.push(now);
  while (arrivals.length && now - arrivals[0] > 1000) arrivals.shift();
  $("rx").textContent = String(Number($("rx").textContent) + 1);
  $("rx-rate").textContent = String(arrivals.length);
}

let retryMs = 500;
function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  const ws = new WebSocket(`${scheme}://${location.host}/ws/telemetry`, WS_PROTOCOLS);
  ws.onopen = () => { retryMs = 500; };
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    countMessage();
    if (message.type === "telemetry") {
      lastTelemetry = performance.now();
      render(message);
      applyLink(message.link, message.connection);
    } else if (message.type === "link") {
      applyLink(message.link, message.connection);
    }
  };
  ws.onclose = () => {
    setView("offline", null, null, "server unreachable — reconnecting…");
    setTimeout(connect, retryMs);
    retryMs = Math.min(retryMs * 2, 5000);
  };
}

async function send(name, params) {
  const out = $("result");
  out.className = "pending";
  out.textContent = `${name}…`;
  try {
    const response = await fetch(`/api/commands/${encodeURIComponent(name)}`, {
      method: "POST",
      headers: { "Content-Type": "application/json", ...AUTH },
      body: JSON.stringify(params),
    });
    const body = await response.json();
    if (response.ok) {
      out.className = "ok";
      out.textContent = body.feedback
        ? `${name}: ${body.feedback.command} ${body.feedback.status}`
        : `${name}: nothing to do`;
    } else {
      out.className = "error";
      out.textContent = `${name}: HTTP ${response.status} — ${body.error}`;
    }
  } catch (error) {
    out.className = "error";
    out.textContent = `${name}: ${error}`;
  }
}

function wireButtons() {
  for (const button of document.querySelectorAll("button[data-command]")) {
    button.addEventListener("click", () => {
      const params = button.dataset.params ? JSON.parse(button.dataset.params) : {};
      send(button.dataset.command, params);
    });
  }
}

async function start() {
  drawInstruments();
  wireButtons();
  setView("connecting");
  try {
    const response = await fetch("/api/status", { headers: AUTH });
    const body = await response.json();
    if (response.status === 401) {
      setView("offline", null, null, "this console needs its token: open the URL the "
        + "server printed (…/#token=…)");
      return;
    }
    if (response.ok) {
      const age = body.link.last_reply_age;
      lastTelemetry = performance.now() - (age === null ? 0 : age * 1000);
      render(body);
    }
    applyLink(body.link || null, body.connection || null);
  } catch (error) {
    setView("offline", null, null, `status unavailable: ${error}`);
  }
  connect();
}

start();
