// cosleec live view: renders the state the server sends (GET /state, then server-sent
// events from /events) and runs the countdowns and ages between two messages. Plain
// JavaScript, no library, nothing loaded from elsewhere; text is set with textContent only.
"use strict";

const clock = { server: 0, at: performance.now(), kind: "real" };
const shown = {}; // section -> JSON of what it shows: a section is redrawn only when that changes

function now() {
  // the runtime's time: as last sent, plus the time since on a real clock (a virtual one moves only when told)
  return clock.kind === "real" ? clock.server + (performance.now() - clock.at) / 1000 : clock.server;
}

function setClock(t) {
  clock.server = t;
  clock.at = performance.now();
}

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined && text !== null) e.textContent = String(text);
  return e;
}

function seconds(x) {
  if (x < 0) x = 0;
  if (x < 60) return x.toFixed(1) + " s";
  if (x < 3600) return Math.floor(x / 60) + " min " + String(Math.floor(x % 60)).padStart(2, "0") + " s";
  return Math.floor(x / 3600) + " h " + String(Math.floor((x % 3600) / 60)).padStart(2, "0") + " min";
}

function at(t) {
  return "t = " + (Math.round(t * 10) / 10) + " s";
}

function value(v) {
  if (v === null || v === undefined) return "unknown";
  if (v === true) return "true";
  if (v === false) return "false";
  return String(v);
}

function redraw(name, data, draw) {
  const key = JSON.stringify(data);
  if (shown[name] === key) return;
  shown[name] = key;
  draw(data);
}

// ------------------------------------------------------------------ sections

function header(s) {
  const source = document.getElementById("source");
  source.textContent = (s.source || "rules").split(/[\\/]/).pop(); // the file's name; its path on hover
  source.title = s.source;
  document.getElementById("semantics").textContent = s.semantics;
  document.getElementById("clock-kind").textContent = s.clock === "virtual" ? "virtual clock" : "real clock";
  const box = document.getElementById("counters");
  box.replaceChildren();
  const st = s.stats;
  for (const [label, n, bad] of [
    ["decisions", st.decisions, false],
    ["violations", st.violations, st.violations > 0],
    ["refused actions", st.refused, false],
    ["conflicts", st.conflicts, st.conflicts > 0],
    ["undetermined", st.undetermined, false],
  ]) {
    const c = el("div", "counter" + (bad ? " bad" : ""));
    c.append(el("div", "n", n), el("div", "label", label));
    box.append(c);
  }
}

function obligations(list) {
  const box = document.getElementById("obligations");
  box.replaceChildren();
  if (!list.length) box.append(el("p", "none", "Nothing is owed."));
  for (const o of list) {
    const row = el("div", "obligation");
    const head = el("div", "head");
    head.append(el("span", "what", o.what), el("span", "who", o.rule + " · decision #" + o.decision));
    const bar = el("div", "bar");
    const fill = el("div", "fill");
    bar.append(fill);
    const left = el("div", "left");
    if (o.deadline !== null) {
      row.dataset.start = o.start;
      row.dataset.deadline = o.deadline;
    } else {
      left.textContent = "no deadline";
    }
    row.append(head, bar, left);
    box.append(row);
  }
  tick();
}

function prohibitions(list) {
  const box = document.getElementById("prohibitions");
  box.replaceChildren();
  if (!list.length) return;
  box.append(el("h3", null, "Forbidden for now"));
  for (const o of list) {
    const row = el("div", "obligation forbidden");
    const head = el("div", "head");
    head.append(el("span", "what", o.what), el("span", "who", o.rule + " · decision #" + o.decision));
    const left = el("div", "left");
    if (o.deadline !== null) {
      row.dataset.start = o.start;
      row.dataset.deadline = o.deadline;
      row.dataset.until = "1";
    } else {
      left.textContent = "with no end";
    }
    row.append(head, left);
    box.append(row);
  }
  tick();
}

function layerText(layer) {
  if (layer === null) return "default";
  if (layer === "?") return "undetermined";
  return layer;
}

function decisions(list) {
  const box = document.getElementById("decisions");
  box.replaceChildren();
  if (!list.length) box.append(el("li", "none", "No decision yet."));
  for (const d of list) {
    const li = el("li", "decision" + (d.clause === null ? " undetermined" : ""));
    const head = el("div", "head");
    const where = d.event === "otherwise" ? "otherwise" : d.clause === null ? "undetermined" : d.clause === 0 ? "default" : d.layer;
    head.append(
      el("span", "id", "#" + d.id),
      el("span", "rule", d.rule),
      el("span", "badge " + (d.clause ? "layer" : d.clause === null ? "unknown" : "default"), where),
      el("span", "on", d.event === "otherwise" ? "a deadline was missed" : "on " + d.event),
      el("span", "time", at(d.time)),
    );
    li.append(head);
    li.append(el("div", "requires", "→ " + (d.obligations.length ? d.obligations.join(" and ") : "nothing required")));
    const cut = d.explanation.indexOf(", because ");
    const why = el("div", "why");
    if (cut >= 0) {
      why.append(el("strong", null, "because "), document.createTextNode(d.explanation.slice(cut + 10)));
    } else {
      why.textContent = d.explanation;
    }
    li.append(why);
    if (d.for_people) li.append(el("div", "says", "says: \u201c" + d.for_people + "\u201d"));  // what a person hears
    box.append(li);
  }
}

function violations(list) {
  const box = document.getElementById("violations");
  box.replaceChildren();
  if (!list.length) box.append(el("li", "none", "None."));
  for (const v of list) {
    const li = el("li", "violation");
    const head = el("div", "head");
    const blocked = v.status === "blocked" || v.status === "refused";  // refused: its name before issue 33
    head.append(el("span", "badge violated", blocked ? "blocked" : v.negated ? "happened" : "missed"), el("strong", null, v.what), el("span", "time", at(v.at)));
    const missed = blocked ? "blocked, " + v.by + " forbids it" : v.negated ? "forbidden, and it happened" : "the deadline passed without it";
    li.append(head, el("div", "who", v.rule + ", decision #" + v.decision + ": " + missed));
    if (v.late && v.late.length) li.append(el("div", "late", "it came late, at " + at(v.late[v.late.length - 1])));
    box.append(li);
  }
}

function conflicts(data) {
  const box = document.getElementById("conflicts");
  box.replaceChildren();
  const items = [
    ...data.conflicts.map((c) => ({ t: c.time, cls: "conflict", mark: "conflict", text: c.explanation })),
    ...data.refusals.map((r) => ({ t: r.time, cls: "refusal", mark: "refused", text: r.reason })),
  ].sort((a, b) => b.t - a.t);
  if (!items.length) box.append(el("li", "none", "None."));
  for (const i of items) {
    const li = el("li", i.cls);
    const head = el("div", "head");
    head.append(el("span", "badge " + i.cls, i.mark), el("span", "time", at(i.t)));
    li.append(head, el("div", null, i.text));
    box.append(li);
  }
}

function context(list) {
  const body = document.querySelector("#context tbody");
  body.replaceChildren();
  for (const c of list) {
    const tr = el("tr", c.value === null ? "unknown" : null);
    const age = el("td", "age");
    if (c.since !== null) {
      age.dataset.since = c.since;
      if (c.before) age.dataset.before = "1";
    }
    tr.append(el("td", "name", c.name), el("td", "value " + c.type, value(c.value)), age);
    body.append(tr);
  }
  tick();
}

function rules(list) {
  const body = document.querySelector("#rules tbody");
  body.replaceChildren();
  for (const r of list) {
    const tr = el("tr");
    const now = el("td");
    const kind = r.layer === null ? "default" : r.layer === "?" ? "unknown" : "layer";
    now.append(el("span", "badge " + kind, layerText(r.layer)));
    if (kind === "layer" && r.clauses[r.layer]) now.append(el("span", "cond", " unless " + r.clauses[r.layer]));
    tr.append(el("td", "name", r.name), el("td", "trigger", r.trigger), now);
    body.append(tr);
  }
}

function controls(s) {
  const box = document.getElementById("controls");
  box.hidden = !s.controls;
  if (!s.controls) return;
  const select = document.getElementById("event-name");
  if (select.options.length !== s.events.length) {
    select.replaceChildren(...s.events.map((e) => el("option", null, e)));
  }
  document.getElementById("advance").hidden = s.clock !== "virtual";
}

// ------------------------------------------------------------------ live parts

function tick() {
  // countdowns and ages between two messages
  const t = now();
  document.getElementById("now").textContent = at(t);
  for (const row of document.querySelectorAll("[data-deadline]")) {
    const start = Number(row.dataset.start);
    const deadline = Number(row.dataset.deadline);
    const left = deadline - t;
    const label = row.querySelector(".left");
    if (row.dataset.until) {
      label.textContent = left > 0 ? "for " + seconds(left) + " more (until " + at(deadline) + ")" : "ends now";
      continue;
    }
    const fill = row.querySelector(".fill");
    const span = deadline - start;
    const done = span > 0 ? Math.min(1, Math.max(0, (t - start) / span)) : 1;
    fill.style.width = (done * 100).toFixed(1) + "%";
    row.classList.toggle("urgent", left <= Math.max(5, span * 0.2));
    row.classList.toggle("due", left <= 0);
    label.textContent = left > 0 ? seconds(left) + " left (deadline " + at(deadline) + ")" : "0.0 s left: due now";
  }
  for (const cell of document.querySelectorAll("[data-since]")) {
    const age = seconds(t - Number(cell.dataset.since));
    cell.textContent = cell.dataset.before ? "≥ " + age : age;
  }
}

function render(s) {
  setClock(s.now);
  clock.kind = s.clock;
  redraw("header", { source: s.source, semantics: s.semantics, clock: s.clock, stats: s.stats }, header);
  redraw("controls", { controls: s.controls, events: s.events, clock: s.clock }, controls);
  redraw("obligations", s.obligations, obligations);
  redraw("prohibitions", s.prohibitions, prohibitions);
  redraw("decisions", s.decisions, decisions);
  redraw("violations", s.violations, violations);
  redraw("conflicts", { conflicts: s.conflicts, refusals: s.refusals }, conflicts);
  redraw("context", s.context, context);
  redraw("rules", s.rules, rules);
  document.body.dataset.version = s.version;
  tick();
}

function connected(on) {
  const pill = document.getElementById("connection");
  pill.textContent = on ? "live" : "reconnecting…";
  pill.className = "pill " + (on ? "on" : "off");
}

function listen() {
  const source = new EventSource("/events");
  source.addEventListener("open", () => connected(true));
  source.addEventListener("error", () => connected(false)); // EventSource reconnects by itself
  source.addEventListener("state", (e) => render(JSON.parse(e.data)));
  source.addEventListener("clock", (e) => {
    setClock(JSON.parse(e.data).now);
    tick();
  });
}

async function control(path, body) {
  const out = document.getElementById("control-result");
  try {
    const r = await fetch(path, { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(body) });
    const answer = await r.json();
    out.textContent = answer.ok ? "done" : answer.error;
  } catch (err) {
    out.textContent = String(err);
  }
}

function wire() {
  document.getElementById("send-event").addEventListener("submit", (e) => {
    e.preventDefault();
    control("/control/event", { event: document.getElementById("event-name").value });
  });
  document.getElementById("advance").addEventListener("submit", (e) => {
    e.preventDefault();
    control("/control/advance", { seconds: Number(document.getElementById("advance-seconds").value) });
  });
}

wire();
fetch("/state").then((r) => r.json()).then(render).finally(listen);
setInterval(tick, 100);
