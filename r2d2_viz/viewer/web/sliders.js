// joint_state_publisher_gui in r2d2-viz's page: a slider per actuated joint (config.joints, from --motion
// sliders), each labelled with its joint's name and spanning its limits; moves are POSTed to `event` (relative:
// under this page's token) as {tool: "Joints", joint, position}, at most 10 a second while dragging and the last
// value always; "centre" and "randomise" set every slider here and send them as one {tool: "Joints", positions}.
const config = JSON.parse(document.getElementById("r2d2-config").textContent);
const joints = config.joints ?? [];
const PERIOD_MS = 100;
const BATCH = 40; // joints per positions event (the server takes 4 kB bodies)
const status = document.getElementById("status");
const say = (text) => { status.textContent = text; status.title = text; };

async function post(event) {
  const response = await fetch("event", { method: "POST", body: JSON.stringify(event),
    headers: { "Content-Type": "application/json" } });
  const answer = await response.json().catch(() => ({ error: `${response.status} ${response.statusText}` }));
  const line = answer.line ?? `error: ${answer.error}`;
  (window.r2d2 ??= { lines: [] }).lines?.push(line);
  say(line);
}

function build(panel) {
  document.getElementById("viewer").classList.add("with-sliders");
  const head = document.createElement("div");
  head.className = "head";
  head.innerHTML = '<span>Joints</span><button data-act="centre">Centre</button><button data-act="randomise">Randomise</button>';
  panel.append(head);
  const rows = new Map();
  for (const joint of joints) {
    const row = document.createElement("label");
    row.className = "joint";
    const unit = joint.type === "prismatic" ? "m" : "rad";
    row.innerHTML = `<span class="name"></span><span class="value"></span><input type="range">`;
    row.querySelector(".name").textContent = joint.name;
    row.title = `${joint.name} (${joint.type}): ${joint.lower} … ${joint.upper} ${unit}`;
    const input = row.querySelector("input");
    Object.assign(input, { min: joint.lower, max: joint.upper, step: (joint.upper - joint.lower) / 1000 || 0.001 });
    input.value = joint.value;
    input.dataset.joint = joint.name;
    const shown = row.querySelector(".value");
    const show = () => { shown.textContent = `${Number(input.value).toFixed(3)} ${unit}`; };
    show();
    let last = 0, pending = null;
    const send = () => { last = Date.now(); pending = null; void post({ tool: "Joints", joint: joint.name, position: Number(input.value) }); };
    input.addEventListener("input", () => {
      show();
      if (Date.now() - last >= PERIOD_MS) send();
      else if (pending === null) pending = setTimeout(send, PERIOD_MS - (Date.now() - last));
    });
    input.addEventListener("change", () => { if (pending !== null) clearTimeout(pending); send(); });
    rows.set(joint.name, { input, show, joint });
    panel.append(row);
  }
  async function setAll(value) {
    const positions = {};
    for (const { input, show, joint } of rows.values()) {
      input.value = value(joint);
      show();
      positions[joint.name] = Number(input.value);
    }
    const names = Object.keys(positions);
    for (let i = 0; i < names.length; i += BATCH) {
      await post({ tool: "Joints", positions: Object.fromEntries(names.slice(i, i + BATCH).map((n) => [n, positions[n]])) });
    }
  }
  head.querySelector('[data-act="centre"]').addEventListener("click", () => void setAll((j) => j.zero));
  head.querySelector('[data-act="randomise"]').addEventListener("click",
    () => void setAll((j) => j.lower + Math.random() * (j.upper - j.lower)));
}

const panel = document.getElementById("sliders");
if (joints.length && panel) build(panel);
