// dura dashboard: the page follows the server's event stream (/api/stream) and never
// polls. Views arrive whole ("goals", "plan", ...) and items one by one ("event",
// "observation"); the pictures come drawn by the server (executive/dashboard/*.py).
"use strict";

const OPEN_GOALS = new Set(["pending", "planned", "executing"]);
const SPARK_SECONDS = 300;
const EVENTS_SHOWN = 400;
const STALE_SECONDS = 10;  // an observation older than this no longer says how things are
const VIEWS = ["status", "goals", "plan", "components"];  // "live" once each has come

const page = {
  events: [],
  kinds: new Set(),
  components: [],
  tracks: new Map(),
  steps: [],
  selectedStep: null,
  selectedNode: null,
  clockSkew: 0,
  loaded: new Set(),  // the views that came since the stream opened
};

function $(id) { return document.getElementById(id); }

// An element with text children (never markup: text from the robot stays text).
function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (value === null || value === undefined || value === false) continue;
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value === true ? "" : String(value));
  }
  for (const child of children.flat()) {
    if (child === null || child === undefined) continue;
    node.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return node;
}

// A number as every view of dura writes it (executive.bus.wording.number): whole numbers
// as they are, others rounded to two decimals without trailing zeros (0.05118 -> 0.05).
function number(value) {
  const n = Number(value);
  return Number.isInteger(n) ? String(n) : String(Number(n.toFixed(2)));
}

function badge(state) {
  return el("span", { class: "badge " + String(state).replace(/\s+/g, "-") }, state);
}

function clock(stamp) {
  if (!stamp) return "-";
  return new Date(stamp * 1000).toLocaleTimeString([], { hour12: false });
}

function fill(tbody, rows) {
  tbody.replaceChildren(...rows);
}

// --- views ------------------------------------------------------------------------------

function showStatus(data) {
  $("robot").textContent = data.robot;
  document.title = `dura ${data.robot}`;
  document.body.classList.toggle("fleet", Boolean(data.fleet));  // its robots' own views hide
  page.alive = data.alive;
  page.problem = data.problem;
  showLink();
}

function showLink() {
  const link = $("link");
  if (!page.connected) {
    link.className = "link connecting";
    link.textContent = "reconnecting…";
  } else if (!VIEWS.every((v) => page.loaded.has(v))) {  // not "live" over an empty page
    link.className = "link connecting";
    link.textContent = "loading…";
  } else if (!page.alive || page.problem) {
    link.className = "link down";
    link.textContent = page.alive ? "executive: " + page.problem : "executive not running";
    link.title = page.problem || "";
  } else {
    link.className = "link live";
    link.textContent = "live";
    link.title = "";
  }
}

function showGoals(data) {
  const rows = data.goals.map((g) => el("tr", { "data-goal": g.id, "data-state": g.state },
    el("td", null, g.id),
    el("td", null, badge(g.state)),
    el("td", null, g.priority),
    el("td", null, g.deadline === null ? "-" : `${g.deadline} s`),
    el("td", null, g.source),
    el("td", { class: "expr" }, g.expression),
    el("td", { class: "reason" }, g.reason || ""),
    el("td", null, OPEN_GOALS.has(g.state)
      ? el("button", { class: "small", type: "button", onclick: () => cancelGoal(g.id) }, "cancel")
      : ""),
  ));
  fill(document.querySelector("#goal-table tbody"), rows.reverse());
}

function showPlan(data) {
  $("plan-title").textContent = data.title;
  $("plan-chart").innerHTML = data.svg;  // drawn by the server, text escaped there
  page.steps = data.steps;
  if (page.selectedStep !== null) showStep(page.selectedStep);
}

function showStep(index) {
  const step = page.steps.find((s) => s.index === index);
  if (step) $("step-details").textContent = step.details.join("\n");
}

function showComponents(data) {
  $("graph").innerHTML = data.svg;  // drawn by the server, text escaped there
  page.components = data.components;
  if (page.selectedNode !== null) showNode(page.selectedNode);
  const configurations = data.configurations.map((t) => el("tr", null,
    el("td", null, `task ${t.id} ${t.name}`),
    el("td", null, badge(t.state)),
    el("td", { class: "mono" }, Object.entries(t.providers).sort()
      .map(([capability, provider]) => `${capability} → ${provider}`).join(", ") || "-"),
  ));
  if (configurations.length === 0) {
    configurations.push(el("tr", null, el("td", { colspan: 3 }, "no task runs")));
  }
  fill(document.querySelector("#configuration-table tbody"), configurations);
  const rows = data.components.map((c) => el("tr", { "data-component": c.name, "data-state": c.state },
    el("td", null, c.name, el("br"), el("small", null, c.kind)),
    el("td", null, badge(c.state), c.diagnosed ? " diagnosed" : ""),
    el("td", null, c.max_faults ? `${c.faults} / ${c.max_faults}` : c.faults || "0"),
    el("td", null, c.tasks.join(", ")),
    el("td", { class: "reason" }, c.reason || "",
      c.output.length && c.state !== "running"  // why it last failed, while that matters
        ? el("pre", { class: "output" }, c.output.join("\n")) : null),
  ));
  fill(document.querySelector("#component-table tbody"), rows);
  showDiagnosis(data.diagnosis || {});
  const select = $("filter-component");
  if (select.options.length <= 1) {
    for (const c of data.components) select.append(el("option", { value: c.name }, c.name));
  }
}

function showNode(name) {
  const node = [...$("graph").querySelectorAll("g.node")].find((g) => g.dataset.node === name);
  const title = node && node.querySelector("title");
  if (title) $("node-details").textContent = title.textContent;
}

function showDiagnosis(d) {
  const box = $("diagnosis");
  if (!d.status) { box.textContent = "no diagnosis yet"; return; }
  const parts = [el("div", null, badge(d.status === "OK" ? "ok" : d.status.toLowerCase()),
    d.status === "OK" ? " every observation is explained: nothing is faulty" :
      ` ${d.diagnoses.length} minimal diagnoses` +
      (d.elapsed ? ` (${(d.elapsed * 1000).toFixed(1)} ms)` : ""))];
  if (d.diagnoses && d.diagnoses.length) {
    parts.push(el("div", null, d.diagnoses.map((set) => el("span", { class: "set" }, set.join(", ")))));
  }
  if (d.failed && d.failed.length) {
    parts.push(el("div", null, "failed: " + d.failed.map((o) =>
      `${o.type}[${(o.resource || []).join(", ")}]`).join(", ")));
  }
  box.replaceChildren(...parts);
}

// --- observations -----------------------------------------------------------------------

function keepTrack(item, history) {
  const track = page.tracks.get(item.key) || { history: [] };
  Object.assign(track, item);
  if (history) track.history = history;
  page.tracks.set(item.key, track);
  return track;
}

function showObservations(data) {
  page.tracks.clear();
  page.clockSkew = Date.now() / 1000 - data.now;
  for (const item of data.observations) keepTrack(item, item.history);
  drawObservations();
}

function addObservations(data) {
  page.clockSkew = Date.now() / 1000 - data.now;
  for (const item of data.observations) {
    const track = keepTrack(item, null);
    track.history.push(item.point);
  }
  drawObservations();
}

function sparkline(points, name) {
  const now = Date.now() / 1000 - page.clockSkew;
  const values = points.filter(([t, v]) => t >= now - SPARK_SECONDS && typeof v[name] === "number")
    .map(([t, v]) => [t, v[name]]);
  if (values.length < 2) return null;
  const seconds = Math.min(SPARK_SECONDS, Math.max(10, now - values[0][0]));
  const low = Math.min(...values.map((p) => p[1]));
  const high = Math.max(...values.map((p) => p[1]));
  const span = high - low || 1;
  const line = values.map(([t, v]) =>
    `${(118 - (now - t) / seconds * 116).toFixed(1)},${(23 - (v - low) / span * 20).toFixed(1)}`).join(" ");
  const picture = document.createElementNS("http://www.w3.org/2000/svg", "svg");
  picture.setAttribute("viewBox", "0 0 120 26");
  const polyline = document.createElementNS("http://www.w3.org/2000/svg", "polyline");
  polyline.setAttribute("points", line);
  polyline.setAttribute("fill", "none");
  polyline.setAttribute("stroke", "#2f6fb0");
  polyline.setAttribute("stroke-width", "1.5");
  picture.append(polyline);
  const label = `${name} from ${number(low)} to ${number(high)} in the last ${Math.round(seconds)} s`;
  return el("span", { class: "spark", title: label }, picture, name);
}

function drawObservations() {
  const now = Date.now() / 1000 - page.clockSkew;
  for (const track of page.tracks.values()) {
    const cutoff = now - SPARK_SECONDS;
    while (track.history.length && track.history[0][0] < cutoff) track.history.shift();
  }
  const rows = [...page.tracks.values()].sort((a, b) => a.key.localeCompare(b.key)).map((t) => {
    // an old failure (its component stopped, say) is grey, not red: it is no longer news
    const stale = now - t.stamp > STALE_SECONDS;
    const failed = !stale && typeof t.observation === "number" && t.observation < 0;
    const values = Object.entries(t.values).map(([k, v]) => `${k} ${number(v)}`);
    const names = Object.keys(t.values);
    return el("tr", { "data-observer": t.observer, "data-failed": failed ? "yes" : "no",
                      class: stale ? "stale" : null },
      el("td", null, t.observer, el("br"), el("small", null, t.type)),
      el("td", { class: "mono" }, t.resource.join(", ") +
        (t.callerids.length ? ` from ${t.callerids.join(", ")}` : "")),
      el("td", { class: failed ? "fail" : "", title: t.verbose }, `${t.message} (${t.observation})`),
      el("td", { class: "mono" }, values.join(", ")),
      el("td", null, names.map((n) => sparkline(t.history, n))),
      el("td", null, `${Math.max(0, now - t.stamp).toFixed(1)} s`),
    );
  });
  fill(document.querySelector("#observation-table tbody"), rows);
}

// --- events -----------------------------------------------------------------------------

function showEvents(data) {
  page.events = data.events.slice();
  for (const e of page.events) page.kinds.add(e.kind);
  refreshKinds();
  drawEvents(false);
}

function addEvents(data) {
  for (const e of data.events) {
    page.events.push(e);
    page.kinds.add(e.kind);
  }
  if (page.events.length > 2000) page.events.splice(0, page.events.length - 2000);
  refreshKinds();
  drawEvents(true);
}

function refreshKinds() {
  const select = $("filter-kind");
  const known = new Set([...select.options].map((o) => o.value));
  for (const kind of [...page.kinds].sort()) {
    if (!known.has(kind)) select.append(el("option", { value: kind }, kind));
  }
}

function mentions(event, name) {
  const pattern = new RegExp(`(^|[^A-Za-z0-9_])${name.replace(/[^A-Za-z0-9_-]/g, "")}($|[^A-Za-z0-9_])`);
  return pattern.test(event.subject || "") || pattern.test(JSON.stringify(event.data || {}));
}

function aboutGoal(event, id) {
  const data = event.data || {};
  return event.subject === `goal ${id}` || (data.goals || []).includes(id) ||
    (data.goal_ids || []).includes(id) || data.goal === id;
}

function details(event) {
  // the server's readable line (executive/bus/event_text.py), else the raw data
  if (event.text) return event.text;
  return [event.subject, ...Object.entries(event.data || {}).map(([k, v]) =>
    `${k}=${typeof v === "object" ? JSON.stringify(v) : v}`)].join("  ");
}

function drawEvents(fresh) {
  const kind = $("filter-kind").value;
  const goal = parseInt($("filter-goal").value, 10);
  const component = $("filter-component").value;
  const shown = page.events.filter((e) => (!kind || e.kind === kind) &&
    (!goal || aboutGoal(e, goal)) && (!component || mentions(e, component)));
  const newest = shown.slice(-EVENTS_SHOWN).reverse();
  const lastId = page.lastEventId || 0;
  fill(document.querySelector("#event-table tbody"), newest.map((e) =>
    el("tr", { "data-kind": e.kind, class: fresh && e.id > lastId ? "fresh" : "" },
      el("td", null, e.id),
      el("td", null, clock(e.stamp)),
      el("td", null, e.kind),
      el("td", null, details(e)),
    )));
  page.lastEventId = Math.max(lastId, ...page.events.map((e) => e.id || 0));
}

// --- changes ----------------------------------------------------------------------------

async function post(url, body) {
  const response = await fetch(url, {
    method: "POST",
    headers: { "content-type": "application/json" },
    body: JSON.stringify(body || {}),
  });
  let answer = {};
  try { answer = await response.json(); } catch (e) { answer = { error: response.statusText }; }
  if (!response.ok) throw new Error(answer.error || response.statusText);
  return answer;
}

function say(text, ok) {
  const message = $("goal-message");
  message.textContent = text;
  message.className = "message " + (ok ? "ok" : "error");
}

async function addGoal(event) {
  event.preventDefault();
  const expression = $("goal-expression").value.trim();
  const priority = $("goal-priority").value.trim();
  const deadline = $("goal-deadline").value.trim();
  const body = { expression, priority: priority === "" ? 0 : Number(priority) };
  if (deadline !== "") body.deadline = Number(deadline);
  const button = event.target.querySelector("button");
  button.disabled = true;
  try {
    const answer = await post("/api/goals", body);
    say(`goal ${answer.goal.id} added: ${answer.goal.expression} (${answer.goal.state})`, true);
    $("goal-expression").value = "";
  } catch (e) {
    say(`refused: ${e.message}`, false);
  } finally {
    button.disabled = false;
  }
}

async function cancelGoal(id) {
  try {
    const answer = await post(`/api/goals/${id}/cancel`);
    say(`goal ${answer.goal.id} cancelled`, true);
  } catch (e) {
    say(`refused: ${e.message}`, false);
  }
}

// --- navigation and the stream ----------------------------------------------------------

function route() {
  const view = (location.hash || "#all").slice(1);
  const known = ["all", "goals", "plan", "components", "observations", "events"];
  document.body.dataset.view = known.includes(view) ? view : "all";
  for (const a of document.querySelectorAll("nav a")) {
    a.classList.toggle("current", a.dataset.view === document.body.dataset.view);
  }
}

function listen() {
  const source = new EventSource("/api/stream");
  const on = (name, handler) => source.addEventListener(name, (message) => {
    handler(JSON.parse(message.data));
    if (!page.loaded.has(name)) {
      page.loaded.add(name);
      showLink();
    }
  });
  on("status", showStatus);
  on("goals", showGoals);
  on("plan", showPlan);
  on("components", showComponents);
  on("observations", showObservations);
  on("events", showEvents);
  on("event", addEvents);
  on("observation", addObservations);
  source.addEventListener("open", () => { page.connected = true; page.loaded.clear(); showLink(); });
  source.addEventListener("error", () => { page.connected = false; showLink(); });
}

function pointAt(container, selector, handler) {
  const pick = (event) => {
    const target = event.target.closest(selector);
    if (target) handler(target);
  };
  container.addEventListener("mouseover", pick);
  container.addEventListener("click", pick);
}

document.addEventListener("DOMContentLoaded", () => {
  route();
  window.addEventListener("hashchange", route);
  $("goal-form").addEventListener("submit", addGoal);
  for (const id of ["filter-kind", "filter-goal", "filter-component"]) {
    $(id).addEventListener("input", () => drawEvents(false));
  }
  $("event-filters").addEventListener("submit", (e) => e.preventDefault());
  pointAt($("plan-chart"), "g.step", (g) => {
    page.selectedStep = Number(g.dataset.step);
    showStep(page.selectedStep);
  });
  pointAt($("graph"), "g.node", (g) => {
    page.selectedNode = g.dataset.node;
    showNode(page.selectedNode);
  });
  setInterval(() => { if (page.tracks.size) drawObservations(); }, 1000);  // ages, not the server
  listen();
});
