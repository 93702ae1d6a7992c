// r2d2-viz's page: Rerun's web viewer (rerun-notebook's widget.js, an anywidget module) driven through a small
// model, and RViz's tools on a toolbar. A click in the 3D view comes back as the viewer's raw
// `selection_change` event with the picked position (in the view's fixed frame); the page collects the clicks a
// tool needs and POSTs them to `event` (relative: under this page's token). Python does the rest.
import widget from "./widget.js";

const config = JSON.parse(document.getElementById("r2d2-config").textContent);
const TOOLBAR_PX = 36;
const CLICKS = { "2D Pose Estimate": 2, "2D Goal Pose": 2, "Publish Point": 1, Measure: 2 };
const ONE_SHOT = new Set(["2D Pose Estimate", "2D Goal Pose", "Publish Point"]); // as in RViz
const ON_GROUND = new Set(["2D Pose Estimate", "2D Goal Pose"]); // RViz's pose tools: the click's ray on z = 0
const TELEOP_PERIOD_MS = 100; // 10 Hz while held

const status = document.getElementById("status");
const say = (text) => { status.textContent = text; status.title = text; };

// --- the anywidget model rerun-notebook's widget reads -------------------------------------------------------
const listeners = new Map();
const state = {
  _url: config.recording ? new URL(config.recording, location.href).href : null, // the RRD stream, as it grows
  _panel_states: null,
  _width: "auto",
  _height: Math.max(200, window.innerHeight - TOOLBAR_PX),
  _fallback_token: null,
  _theme: "dark",
};
const model = {
  get: (key) => state[key],
  set: (key, value) => { state[key] = value; emit(`change:${key}`, null, value); },
  save_changes: () => {},
  on: (name, callback) => { if (!listeners.has(name)) listeners.set(name, new Set()); listeners.get(name).add(callback); },
  off: (name, callback) => { if (callback) listeners.get(name)?.delete(callback); else listeners.delete(name); },
  send: (message) => setTimeout(() => onViewerEvent(message), 0), // never call the viewer from its callback
};
function emit(name, ...args) { for (const callback of listeners.get(name) ?? []) callback(...args); }
window.addEventListener("resize", () => model.set("_height", Math.max(200, window.innerHeight - TOOLBAR_PX)));

// --- tools ----------------------------------------------------------------------------------------------------
let active = null;
let clicks = [];
window.r2d2 = { ready: false, picks: [], lines: [], events: [] }; // for scripts and tests: what the viewer reported

function activate(tool) {
  active = active === tool ? null : tool;
  clicks = [];
  for (const b of document.querySelectorAll("button.tool")) b.classList.toggle("active", b.dataset.tool === active);
  if (active) say(`${active}: click ${CLICKS[active] === 2 ? "the position" : "a point"} in the 3D view`);
}
for (const button of document.querySelectorAll("button.tool")) {
  button.addEventListener("click", () => activate(button.dataset.tool));
}

async function post(event) {
  try {
    const response = await fetch("event", { method: "POST", body: JSON.stringify(event),
      headers: { "Content-Type": "application/json" } });
    const answer = await response.json().catch(() => ({ error: `${response.status} ${response.statusText}` }));
    const line = answer.line ?? `error: ${answer.error}`;
    window.r2d2.lines.push(line);
    if (event.tool !== "Teleop" || answer.error) say(line);
  } catch (err) {
    say(`error: ${err}`);
  }
}

// The 3D view's eye, for the pose tools' rays: Rerun keeps it in the viewer's blueprint (EyeControls3D, saved as
// the view is orbited); the server serves rerun-notebook's widget with its viewer on globalThis.r2d2Viewer, and
// reads the eye out of the blueprint sent to `eye`. null when there is none (the tool takes the point picked).
async function viewEye() {
  const viewer = globalThis.r2d2Viewer;
  if (!viewer) return null;
  try {
    const blueprint = await new Response(viewer.save_blueprint()).arrayBuffer();
    const response = await fetch("eye", { method: "POST", body: blueprint,
      headers: { "Content-Type": "application/octet-stream" } });
    const answer = await response.json();
    return Array.isArray(answer.eye) ? answer.eye : null;
  } catch {
    return null;
  }
}

// The recording comes as an HTTP .rrd, which the viewer plays from its start like a file: once its timeline is
// there (the first time report of each recording), ask it to follow the latest data, as it does a live stream.
const following = new Set();
function followLive(event) {
  if (event?.type !== "time_update" || following.has(event.recording_id)) return;
  following.add(event.recording_id);
  emit("msg:custom", { type: "time_ctrl", play: "following" }, []);
}

function onViewerEvent(message) {
  if (message === "ready") { window.r2d2.ready = true; return; }
  let event;
  try { event = typeof message === "string" ? JSON.parse(message) : message; } catch { return; }
  window.r2d2.events = [...window.r2d2.events.slice(-19), event]; // the last 20, for scripts and tests
  followLive(event);
  if (event?.type !== "selection_change" || !active) return;
  const item = (event.items ?? []).find((i) => Array.isArray(i.position));
  if (!item) {
    if ((event.items ?? []).length) say(`${active}: no position there; click the ground or an object`);
    return;
  }
  const position = item.position.map(Number);
  window.r2d2.picks.push({ tool: active, position, entity: item.entity_path ?? null });
  clicks.push(position);
  if (clicks.length < CLICKS[active]) {
    say(`${active}: (${position.map((v) => v.toFixed(2)).join(", ")}); now click the ${active === "Measure" ? "second point" : "heading"}`);
    return;
  }
  const tool = active;
  const pick = { tool, points: clicks, entity: item.entity_path ?? null };
  if (ON_GROUND.has(tool)) void viewEye().then((eye) => post(eye ? { ...pick, eye } : pick));
  else void post(pick);
  clicks = [];
  if (ONE_SHOT.has(tool)) activate(tool); // back to no tool, as RViz returns to Interact
}

// --- teleop: arrow keys or the pad, 10 Hz while held, zero on release and when the page goes ------------------
const held = new Set();
const KEYS = { ArrowUp: "forward", ArrowDown: "backward", ArrowLeft: "left", ArrowRight: "right" };
let timer = null;
const speed = (id) => Math.max(0, Number(document.getElementById(id).value) || 0);
function twist() {
  const linear = (held.has("forward") - held.has("backward")) * speed("linear");
  const angular = (held.has("left") - held.has("right")) * speed("angular");
  return { tool: "Teleop", linear, angular };
}
function drive() {
  for (const b of document.querySelectorAll("button.drive")) b.classList.toggle("held", held.has(b.dataset.drive));
  if (held.size && timer === null) {
    void post(twist());
    timer = setInterval(() => void post(twist()), TELEOP_PERIOD_MS);
  } else if (!held.size && timer !== null) {
    clearInterval(timer);
    timer = null;
    void post({ tool: "Teleop", linear: 0, angular: 0 });
    say("Teleop: stopped");
  }
}
for (const button of document.querySelectorAll("button.drive")) {
  const press = (e) => { e.preventDefault(); held.add(button.dataset.drive); drive(); };
  const release = () => { if (held.delete(button.dataset.drive)) drive(); };
  button.addEventListener("pointerdown", press);
  button.addEventListener("pointerup", release);
  button.addEventListener("pointerleave", release);
  button.addEventListener("pointercancel", release);
}
const typing = () => document.activeElement?.tagName === "INPUT";
window.addEventListener("keydown", (e) => {
  if (!(e.key in KEYS) || typing()) return;
  e.preventDefault(); e.stopPropagation();
  if (!held.has(KEYS[e.key])) { held.add(KEYS[e.key]); drive(); }
}, true);
window.addEventListener("keyup", (e) => {
  if (!(e.key in KEYS) || typing()) return;
  e.preventDefault(); e.stopPropagation();
  if (held.delete(KEYS[e.key])) drive();
}, true);
function stopOnLeave() {
  if (timer === null) return;
  clearInterval(timer);
  timer = null;
  held.clear();
  navigator.sendBeacon("event", JSON.stringify({ tool: "Teleop", linear: 0, angular: 0 }));
}
window.addEventListener("pagehide", stopOnLeave);
window.addEventListener("blur", () => { if (held.size) { held.clear(); drive(); } });

// --- the viewer -----------------------------------------------------------------------------------------------
const el = document.getElementById("viewer");
widget.render({ model, el });
say("loading the viewer…");
const waitReady = setInterval(() => {
  if (window.r2d2.ready) { clearInterval(waitReady); say("ready: pick a tool"); }
}, 200);
