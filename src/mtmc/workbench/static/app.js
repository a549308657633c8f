// The measurement-graph workbench: the page. No maths here: every number comes from the
// server (mtmc.graph, mtmc.uncertainty); the page edits the graph's JSON view, draws it
// with cytoscape.js and shows what the server returns.
import cytoscape from "./vendor/cytoscape.esm.min.mjs";

const $ = (sel) => document.querySelector(sel);
const DEBOUNCE_MS = 120;
const PLACE_KEYS = ["value", "u", "dist", "unit"];

const state = {
  file: "",
  view: null,          // the graph view: {title, units, probe, places, transitions}
  layout: {},          // node -> [x, y] from the library's layout() (for nodes without pos)
  palette: null,
  types: {},           // place -> type, as last checked
  results: {},         // place -> {type, parts}
  errors: [],
  warnings: [],
  selected: null,      // {kind: "place"|"transition"|"arc", name, ...}
  undo: [],
  redo: [],
  saved: "",           // the view as saved, to tell whether an edit is pending
  dirty: false,
  seq: 0,
  client: Math.random().toString(36).slice(2),  // this page's requests, numbered by seq
  timer: null,
  arcFrom: null,
  fitted: false,       // the view fitted to the first results' labels
};
let cy = null;

// ------------------------------------------------------------------ server
async function call(path, body) {
  const init = body === undefined ? {} : {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  };
  const resp = await fetch(path, init);
  let data;
  try { data = await resp.json(); } catch { data = { error: `${resp.status} ${resp.statusText}` }; }
  if (!resp.ok) throw new Error(data.error || `${resp.status}`);
  return data;
}

function notice(text, refused = false) {
  const n = $("#notice");
  n.textContent = text;
  n.title = text;
  n.className = refused ? "refused" : "";
}

function setStatus(text, kind = "") {
  const s = $("#status");
  s.textContent = text;
  s.className = "status " + kind;
}

// ------------------------------------------------------------------ the view
const clone = (x) => JSON.parse(JSON.stringify(x));
const placeOf = (name) => state.view.places.find((p) => p.name === name);
const transOf = (name) => state.view.transitions.find((t) => t.name === name);
const snapshot = () => JSON.stringify(state.view);

function addImplicitPlaces() {
  // a place a transition produces without declaring it: shown, written once it has a pos
  for (const t of state.view.transitions) {
    if (t.out && !placeOf(t.out)) {
      state.view.places.push({ src: null, declared: false, name: t.out, type: state.types[t.out] });
    }
  }
}

function setView(view, layout) {
  state.view = view;
  state.layout = layout || {};
  addImplicitPlaces();
}

function markDirty() {
  const dirty = snapshot() !== state.saved;
  $("#dirty").textContent = dirty ? "● unsaved" : "";
  if (dirty !== state.dirty) {
    state.dirty = dirty;
    call("api/dirty", { dirty }).catch(() => {});
  }
}

function edit(change, { recompute = true } = {}) {
  const before = snapshot();
  change(state.view);
  if (snapshot() === before) return;
  state.undo.push(before);
  state.redo = [];
  afterEdit(recompute);
}

function afterEdit(recompute) {
  markDirty();
  draw();
  inspect();
  if (recompute) schedule();
}

function undo() {
  if (!state.undo.length) return;
  state.redo.push(snapshot());
  state.view = JSON.parse(state.undo.pop());
  afterEdit(true);
}

function redo() {
  if (!state.redo.length) return;
  state.undo.push(snapshot());
  state.view = JSON.parse(state.redo.pop());
  afterEdit(true);
}

function uniqueName(stem) {
  const taken = new Set([...state.view.places.map((p) => p.name), ...state.view.transitions.map((t) => t.name)]);
  for (let i = 1; ; i++) if (!taken.has(stem + i)) return stem + i;
}

function displayPos(name) {
  const node = placeOf(name) || transOf(name);
  if (node && node.pos) return { x: node.pos[0], y: node.pos[1] };
  if (state.layout[name]) return { x: state.layout[name][0], y: state.layout[name][1] };
  return null;
}

function storeAllPositions(view) {
  // layout() uses stored positions only when every node has one: store them all at once
  const round = (v) => Math.round(v * 10) / 10;
  for (const n of [...view.places, ...view.transitions]) {
    const el = cy.getElementById(n.name);
    if (el.nonempty()) n.pos = [round(el.position("x")), round(el.position("y"))];
  }
}

// ------------------------------------------------------------------ drawing
function fmtPart(part) {
  const u = part.u.join(", ");
  if (part.estimate.length === 1) return `${part.estimate[0]} ± ${part.u[0]} ${part.unit}`;
  return `u = ${u} ${part.unit}`;
}

function placeLabel(p) {
  const type = p.type || state.types[p.name] || "?";
  const lines = [p.name, type + (isMarked(p) ? " ●" : "")];
  const r = state.results[p.name];
  if (r && r.parts.length) lines.push((r.parts.length > 1 ? r.parts[0].part + " " : "") + fmtPart(r.parts[0]));
  return lines.join("\n");
}

const isMarked = (p) => PLACE_KEYS.slice(0, 3).some((k) => p[k] !== undefined && p[k] !== null);

function ordered(op) {
  return op !== "middle";
}

function elements() {
  const errs = {};
  for (const e of state.errors) if (e.node) errs[e.node] = e.text;
  const els = [];
  for (const p of state.view.places) {
    els.push({
      group: "nodes",
      data: { id: p.name, kind: "place", label: placeLabel(p), error: errs[p.name] || "" },
      position: displayPos(p.name) || { x: 0, y: 0 },
      classes: "place" + (errs[p.name] ? " error" : "") + (isMarked(p) ? " marked" : ""),
    });
  }
  for (const t of state.view.transitions) {
    els.push({
      group: "nodes",
      data: { id: t.name, kind: "transition", label: `${t.name}\n${t.op}`, error: errs[t.name] || "" },
      position: displayPos(t.name) || { x: 0, y: 0 },
      classes: "transition" + (errs[t.name] ? " error" : ""),
    });
    (t.in || []).forEach((p, i) => {
      if (!placeOf(p)) return;
      els.push({
        group: "edges",
        data: { id: `${p}->${t.name}#${i}`, source: p, target: t.name, index: i,
          label: (t.in.length > 1 && ordered(t.op)) ? String(i + 1) : "" },
      });
    });
    if (t.out && placeOf(t.out)) {
      els.push({ group: "edges", data: { id: `${t.name}->${t.out}`, source: t.name, target: t.out, label: "" } });
    }
  }
  return els;
}

function draw() {
  const sel = state.selected && state.selected.name;
  cy.batch(() => {
    cy.elements().remove();
    cy.add(elements());
    const unplaced = cy.nodes().filter((n) => !displayPos(n.id()));
    if (unplaced.nonempty()) {
      const ext = cy.extent();
      unplaced.forEach((n, i) => n.position({ x: ext.x1 + 80 + 40 * i, y: ext.y1 + 60 }));
    }
    if (sel) cy.getElementById(sel).select();
  });
  $("#cy").dataset.places = String(cy.nodes(".place").length);
  $("#cy").dataset.transitions = String(cy.nodes(".transition").length);
  drawResults();
}

function style() {
  return [
    { selector: "node", style: { label: "data(label)", "text-wrap": "wrap", "font-size": 9, "text-valign": "bottom", "text-margin-y": 3, "border-width": 1.5, "border-color": "#333" } },
    { selector: "node.place", style: { shape: "ellipse", width: 26, height: 26, "background-color": "#fff" } },
    { selector: "node.place.marked", style: { "background-color": "#333", "background-opacity": 0.85 } },
    { selector: "node.transition", style: { shape: "rectangle", width: 34, height: 14, "background-color": "#dfe7f1", "text-valign": "center", "text-margin-y": 0, "font-size": 8, width: 54, height: 24 } },
    { selector: "node.error", style: { "border-color": "#c00", "border-width": 3 } },
    { selector: "node:selected", style: { "border-color": "#2b5d8a", "border-width": 3, "overlay-opacity": 0.08 } },
    { selector: "node.arc-from", style: { "border-color": "#e08a00", "border-width": 3 } },
    { selector: "edge", style: { width: 1.3, "line-color": "#555", "target-arrow-color": "#555", "target-arrow-shape": "triangle", "curve-style": "bezier", label: "data(label)", "font-size": 8, "text-background-color": "#fff", "text-background-opacity": 1 } },
    { selector: "edge:selected", style: { "line-color": "#2b5d8a", "target-arrow-color": "#2b5d8a", width: 2.5 } },
  ];
}

function drawResults() {
  const body = $("#results tbody");
  body.replaceChildren();
  for (const p of state.view.places) {
    const r = state.results[p.name];
    const tr = document.createElement("tr");
    tr.dataset.place = p.name;
    if (state.selected && state.selected.name === p.name) tr.className = "selected";
    const part = r && r.parts[0];
    const cells = [p.name, (r && r.type) || p.type || state.types[p.name] || "",
      part ? (part.part !== "value" ? part.part + " " : "") + part.estimate.join(", ") : "",
      part ? part.u.join(", ") : "", part && part.gum_u ? part.gum_u.join(", ") : "", part ? part.unit : ""];
    cells.forEach((c, i) => {
      const td = document.createElement("td");
      td.textContent = c;
      if (i >= 2 && i <= 4) td.className = "num";
      if (i === 3 && part) { td.classList.add("u"); td.dataset.value = JSON.stringify(part.u_value); }
      if (i === 4 && part && part.gum_u_value) { td.classList.add("gum-u"); td.dataset.value = JSON.stringify(part.gum_u_value); }
      tr.append(td);
    });
    tr.addEventListener("click", () => select({ kind: "place", name: p.name }));
    body.append(tr);
  }
}

function drawMessages() {
  const box = $("#messages");
  box.replaceChildren();
  if (!state.errors.length && !state.warnings.length) return;
  const h = document.createElement("h2");
  h.textContent = "Check";
  box.append(h);
  for (const e of state.errors) {
    const p = document.createElement("p");
    p.className = "error";
    p.dataset.node = e.node || "";
    p.textContent = e.message;
    box.append(p);
  }
  for (const w of state.warnings) {
    const p = document.createElement("p");
    p.className = "warning";
    p.textContent = w;
    box.append(p);
  }
}

// ------------------------------------------------------------------ live uncertainty
function schedule() {
  clearTimeout(state.timer);
  state.seq += 1;            // any answer to an earlier request is stale from now on
  setStatus("computing", "computing");
  state.timer = setTimeout(runNow, DEBOUNCE_MS);
}

async function runNow() {
  const seq = state.seq;
  const selected = state.selected && state.selected.kind === "place" ? state.selected.name : null;
  let out;
  try {
    out = await call("api/run", { seq, client: state.client, graph: state.view, selected });
  } catch (err) {
    if (seq === state.seq) setStatus(String(err.message), "error");
    return;
  }
  if (out.stale || out.seq !== state.seq) return;  // a newer edit is on its way
  state.errors = out.errors || [];
  state.warnings = out.warnings || [];
  if (out.types) state.types = out.types;
  for (const [n, xy] of Object.entries(out.positions || {})) if (!state.layout[n]) state.layout[n] = xy;
  for (const p of state.view.places) if (!p.declared && !p.type && state.types[p.name]) p.type = state.types[p.name];
  state.results = out.places || {};
  drawMessages();
  draw();
  if (!state.fitted && Object.keys(state.results).length) {
    // the first results lengthen the places' labels: fit the view to them once, so that
    // none starts beyond the canvas' edge (later ones leave the user's view as it is)
    cy.fit(undefined, 30);
    state.fitted = true;
  }
  showSummary(out.summary);
  if (state.errors.length) {
    setStatus(`${state.errors.length} error`, "error");
    $("#runinfo").textContent = "";
  } else {
    setStatus("up to date");
    $("#runinfo").textContent = `${out.trials} trials, randomised QMC (Sobol), seed ${out.seed}; GUM: ${out.gum}; ${Math.round(1000 * out.seconds)} ms`;
  }
  document.body.dataset.seq = String(seq);
}

function showSummary(s) {
  const box = $("#summary");
  box.replaceChildren();
  if (!s) return;
  const h = document.createElement("h2");
  h.textContent = `${s.place} (${s.type}): ${Math.round(100 * s.p)} % intervals, ${s.trials} trials`;
  box.append(h);
  const t = document.createElement("table");
  t.innerHTML = "<thead><tr><th></th><th>estimate</th><th>u</th><th>MC interval</th><th>GUM u</th><th>k</th><th>GUM interval</th><th>§8</th></tr></thead>";
  const body = document.createElement("tbody");
  for (const c of s.components) {
    const tr = document.createElement("tr");
    const g = c.gum;
    const cells = [`${c.component} / ${c.unit}`, c.estimate, c.u, `[${c.interval.join(", ")}]`,
      g ? g.u : "", g ? String(g.k) : "", g ? `[${g.interval.join(", ")}]` : "",
      g ? (g.validated ? "GUM validated" : "not validated") : ""];
    cells.forEach((x, i) => {
      const td = document.createElement("td");
      td.textContent = x;
      if (i === 7 && g) td.className = g.validated ? "pass" : "fail";
      tr.append(td);
    });
    body.append(tr);
  }
  t.append(body);
  box.append(t);
  for (const r of s.regions || []) {
    const e = document.createElement("p");
    e.className = "hint";
    e.textContent = `${Math.round(100 * s.p)} % coverage region, ${r.region}: semi-axes ` +
      `${r.semi_axes.join(", ")} ${r.unit} (k = ${r.k}, JCGM 102)`;
    box.append(e);
  }
  const first = s.components.find((c) => c.gum && c.gum.budget.length);
  if (first) {
    const b = document.createElement("p");
    b.className = "hint";
    b.textContent = "budget (" + first.component + "): " +
      first.gum.budget.map((l) => `${l.input} ${l.contribution} (${l.share} %)`).join("; ");
    box.append(b);
  }
}

// ------------------------------------------------------------------ inspector
function field(label, value, onChange, { unit = "", options = null, title = "" } = {}) {
  const lab = document.createElement("label");
  lab.textContent = label + " ";
  if (title) lab.title = title;
  let input;
  if (options) {
    input = document.createElement("select");
    for (const o of options) {
      const opt = document.createElement("option");
      opt.value = o;
      opt.textContent = o === "" ? "—" : o;
      input.append(opt);
    }
    input.value = value ?? "";
  } else {
    input = document.createElement("input");
    input.value = value === undefined || value === null ? "" : (Array.isArray(value) ? value.join(", ") : String(value));
  }
  input.name = label;
  input.addEventListener("change", () => onChange(input.value));
  lab.append(input);
  if (unit) {
    const u = document.createElement("span");
    u.className = "unit";
    u.textContent = " " + unit;
    lab.append(u);
  }
  return lab;
}

function parseValue(text, n) {
  // numbers as numbers; anything else is sent as it is and the graph's parser says what is wrong
  const t = text.trim();
  if (t === "") return null;
  const parts = t.replace(/^\[|\]$/g, "").split(/[,\s]+/).filter((x) => x !== "");
  const nums = parts.map(Number);
  if (nums.every((x) => Number.isFinite(x))) {
    if (n === 1 && nums.length === 1) return nums[0];
    if (nums.length === 1 && n !== 3) return nums[0];
    return nums;
  }
  return t;
}

function lengthUnit() {
  return state.view.units === "um" ? "µm" : "mm";
}

function placeUnit(p) {
  if (p.type === "direction") return "1";
  if (p.type === "real") return p.unit === "deg" ? "deg" : p.unit === "rad" ? "rad" : p.unit === "1" ? "1" : lengthUnit();
  return lengthUnit();
}

function inspect() {
  const box = $("#inspector");
  box.replaceChildren();
  const sel = state.selected;
  const h = document.createElement("h2");
  if (!sel) { box.innerHTML = '<p class="hint">Select a place or a transition.</p>'; return; }
  if (sel.kind === "arc") {
    h.textContent = `arc ${sel.source} → ${sel.target}`;
    box.append(h);
    return;
  }
  if (sel.kind === "place") {
    const p = placeOf(sel.name);
    if (!p) { state.selected = null; return inspect(); }
    h.textContent = `place ${p.name}`;
    box.append(h);
    const unit = placeUnit(p);
    const vec = ["point", "vector", "direction"].includes(p.type);
    box.append(field("name", p.name, (v) => rename(p.name, v.trim())));
    box.append(field("type", p.type || "", (v) => edit((g) => { const q = g.places.find((x) => x.name === p.name); q.type = v; q.declared = true; }), { options: state.palette.place_types }));
    const set = (key, n) => (v) => edit((g) => {
      const q = g.places.find((x) => x.name === p.name);
      const val = key === "dist" || key === "unit" ? (v.trim() || null) : parseValue(v, n);
      if (val === null) delete q[key]; else q[key] = val;
      q.declared = true;
    });
    box.append(field("value", p.value, set("value", vec ? 3 : 1), { unit, title: vec ? "x, y, z" : "" }));
    box.append(field("u", p.u, set("u", vec ? 0 : 1), { unit, title: "standard uncertainty (one, or x, y, z)" }));
    box.append(field("dist", p.dist, set("dist", 0), { title: 'a PDF of the deviation, e.g. uniform(-1e-3, 1e-3)' }));
    if (p.type === "real") box.append(field("unit", p.unit || "", set("unit", 0), { options: ["", "1", "rad", "deg"] }));
    return;
  }
  const t = transOf(sel.name);
  if (!t) { state.selected = null; return inspect(); }
  h.textContent = `transition ${t.name}`;
  box.append(h);
  box.append(field("name", t.name, (v) => rename(t.name, v.trim())));
  box.append(field("op", t.op, (v) => edit((g) => { g.transitions.find((x) => x.name === t.name).op = v; }), { options: Object.keys(state.palette.ops) }));
  const ins = document.createElement("p");
  ins.className = "hint";
  ins.textContent = `in: ${(t.in || []).join(", ") || "—"}; out: ${t.out || "—"}`;
  box.append(ins);
  const params = t.params || {};
  const setp = (key, n) => (v) => edit((g) => {
    const q = g.transitions.find((x) => x.name === t.name);
    q.params = q.params || {};
    const val = key === "dist" || key === "coordinate" ? (v.trim() || null) : parseValue(v, n);
    if (val === null) delete q.params[key]; else q.params[key] = val;
  });
  if (t.op === "meas") {
    box.append(field("at", params.at, setp("at", 3), { unit: lengthUnit(), title: "nominal probed point x, y, z" }));
    box.append(field("direction", params.direction, setp("direction", 3), { title: "probing direction" }));
    box.append(field("coordinate", params.coordinate || "", setp("coordinate", 0), { options: ["", "x", "y", "z"] }));
    for (const k of ["u_axis", "u_probe", "u_perp"]) {
      box.append(field(k, params[k], setp(k, 1), { unit: lengthUnit(), title: "overrides [probe]" }));
    }
    box.append(field("dist", params.dist, setp("dist", 0)));
  }
  const doc = (state.palette.ops[t.op] || { variants: [] }).variants
    .map((v) => `(${[...v.inputs, ...(v.rest ? [`${v.min_rest}+ ${v.rest}`] : []), ...v.suffix].join(", ")}) → ${v.output}`);
  const p = document.createElement("p");
  p.className = "hint";
  p.textContent = `${t.op}: ${doc.join("; ")}`;
  box.append(p);
}

function graphForm() {
  const f = $("#graph-form");
  f.title.value = state.view.title || "";
  f.units.value = state.view.units || "mm";
  for (const k of ["u_axis", "u_probe", "u_perp"]) f[k].value = state.view.probe[k] ?? "";
  for (const el of document.querySelectorAll(".unit-len")) el.textContent = lengthUnit();
}

function bindGraphForm() {
  const f = $("#graph-form");
  f.addEventListener("submit", (e) => e.preventDefault());
  f.title.addEventListener("change", () => edit((g) => { g.title = f.title.value; }, { recompute: false }));
  f.units.addEventListener("change", () => edit((g) => { g.units = f.units.value; }));
  for (const k of ["u_axis", "u_probe", "u_perp"]) {
    f[k].addEventListener("change", () => edit((g) => {
      const v = parseValue(f[k].value, 1);
      if (v === null) delete g.probe[k]; else g.probe[k] = v;
    }));
  }
}

// ------------------------------------------------------------------ editing
function select(sel) {
  state.selected = sel;
  cy.elements().unselect();
  if (sel && sel.kind !== "arc") cy.getElementById(sel.name).select();
  inspect();
  drawResults();
  if (sel && sel.kind === "place") schedule();
  else showSummary(null);
}

function rename(old, name) {
  if (!name || name === old) return;
  if (placeOf(name) || transOf(name)) { notice(`${name} exists already`, true); inspect(); return; }
  edit((g) => {
    for (const p of g.places) if (p.name === old) { p.name = name; }
    for (const t of g.transitions) {
      if (t.name === old) t.name = name;
      t.in = (t.in || []).map((x) => (x === old ? name : x));
      if (t.out === old) t.out = name;
    }
  });
  if (state.layout[old]) state.layout[name] = state.layout[old];
  if (state.selected && state.selected.name === old) state.selected.name = name;
  inspect();
}

function freeSpot() {
  // the first point from the middle of the view, on a spiral of 70-unit steps, where a new
  // node and the two lines of its label (a box of 120 × 70 units) meet no node and no label
  const ext = cy.extent();
  const cx = (ext.x1 + ext.x2) / 2, cyy = (ext.y1 + ext.y2) / 2;
  const gap = 8;
  const boxes = cy.nodes().map((n) => n.boundingBox({ includeLabels: true }));
  const clear = (b) => boxes.every((o) => b.x2 + gap < o.x1 || b.x1 - gap > o.x2 || b.y2 + gap < o.y1 || b.y1 - gap > o.y2);
  for (let i = 0; i < 2000; i++) {
    const r = 70 * Math.ceil(Math.sqrt(i)), a = i * 2.4;
    const at = { x: cx + r * Math.cos(a), y: cyy + r * Math.sin(a) };
    if (clear({ x1: at.x - 60, x2: at.x + 60, y1: at.y - 20, y2: at.y + 50 })) return at;
  }
  return { x: ext.x2 + 120, y: cyy };
}

function addNode(kind, what) {
  const at = freeSpot();
  const name = kind === "place" ? uniqueName(what === "point" ? "p" : what) : uniqueName(what === "meas" ? "m" : "t");
  edit((g) => {
    storeAllPositions(g);
    if (kind === "place") {
      g.places.push({ src: null, declared: true, name, type: what, pos: [Math.round(at.x), Math.round(at.y)] });
    } else {
      const t = { src: null, name, op: what, in: [], out: "", params: {}, pos: [Math.round(at.x), Math.round(at.y)] };
      if (what === "meas") t.params = { at: [0, 0, 0], direction: [0, 0, -1] };
      g.transitions.push(t);
    }
  });
  select({ kind, name });
}

function deleteSelected() {
  const sel = state.selected;
  if (!sel) return;
  edit((g) => {
    if (sel.kind === "place") {
      g.places = g.places.filter((p) => p.name !== sel.name);
      for (const t of g.transitions) {
        t.in = (t.in || []).filter((x) => x !== sel.name);
        if (t.out === sel.name) t.out = "";
      }
    } else if (sel.kind === "transition") {
      const t = g.transitions.find((x) => x.name === sel.name);
      g.transitions = g.transitions.filter((x) => x.name !== sel.name);
      if (t && t.out) g.places = g.places.filter((p) => p.name !== t.out || p.declared);
    } else {
      const t = g.transitions.find((x) => x.name === (sel.sourceKind === "transition" ? sel.source : sel.target));
      if (!t) return;
      if (sel.sourceKind === "transition") {
        const p = g.places.find((x) => x.name === t.out);
        if (p && !p.declared) { p.declared = true; p.type = p.type || state.types[p.name]; }
        t.out = "";
      } else {
        t.in = t.in.filter((_, i) => i !== sel.index);
      }
    }
  });
  select(null);
}

async function tryArc(source, target) {
  let out;
  try {
    out = await call("api/arc", { graph: state.view, source, target, types: state.types });
  } catch (err) {
    notice(err.message, true);
    return;
  }
  if (!out.ok) {
    notice(`arc ${source} → ${target} refused: ${out.message}`, true);
    return;
  }
  notice(`arc ${source} → ${target}`);
  edit((g) => {
    const s = g.places.find((p) => p.name === source);
    if (s) g.transitions.find((t) => t.name === target).in.push(source);
    else g.transitions.find((t) => t.name === source).out = target;
  });
}

function setArcMode(on) {
  $("#arcmode").setAttribute("aria-pressed", String(on));
  cy.autoungrabify(on);
  cy.userPanningEnabled(!on);
  cy.boxSelectionEnabled(!on);
  state.arcFrom = null;
  cy.nodes().removeClass("arc-from");
}

function bindCanvas() {
  const arcMode = () => $("#arcmode").getAttribute("aria-pressed") === "true";
  cy.on("tapstart", "node", (e) => {
    if (!arcMode()) return;
    state.arcFrom = e.target.id();
    e.target.addClass("arc-from");
  });
  cy.on("tapend", (e) => {
    if (!arcMode() || !state.arcFrom) return;
    const from = state.arcFrom;
    const to = e.target !== cy && e.target.isNode && e.target.isNode() ? e.target.id() : null;
    if (to && to !== from) {
      state.arcFrom = null;
      cy.nodes().removeClass("arc-from");
      tryArc(from, to);
    } else if (!to) {
      state.arcFrom = null;
      cy.nodes().removeClass("arc-from");
    }
  });
  cy.on("tap", "node", (e) => {
    if (arcMode()) return;
    select({ kind: e.target.data("kind"), name: e.target.id() });
  });
  cy.on("tap", "edge", (e) => {
    const d = e.target.data();
    const sourceKind = cy.getElementById(d.source).data("kind");
    select({ kind: "arc", source: d.source, target: d.target, index: d.index, sourceKind });
  });
  cy.on("tap", (e) => { if (e.target === cy && !arcMode()) select(null); });
  cy.on("dragfree", "node", () => edit((g) => storeAllPositions(g), { recompute: false }));
}

function bindKeys() {
  document.addEventListener("keydown", (e) => {
    const typing = ["INPUT", "SELECT", "TEXTAREA"].includes(document.activeElement.tagName);
    if ((e.ctrlKey || e.metaKey) && e.key === "s") { e.preventDefault(); save(); return; }
    if (typing) return;
    if ((e.ctrlKey || e.metaKey) && e.key === "z") { e.preventDefault(); undo(); }
    else if ((e.ctrlKey || e.metaKey) && (e.key === "y" || e.key === "Z")) { e.preventDefault(); redo(); }
    else if (e.key === "Delete" || e.key === "Backspace") deleteSelected();
    else if (e.key === "a") setArcMode($("#arcmode").getAttribute("aria-pressed") !== "true");
  });
}

// ------------------------------------------------------------------ files
async function save() {
  let out;
  try {
    out = await call("api/save", { graph: state.view });
  } catch (err) {
    notice(`not saved: ${err.message}`, true);
    return;
  }
  // the file's entries are renumbered by the save: the view is the file's from now on
  const before = state.view;
  setView(out.view, Object.assign({}, state.layout, out.positions));
  for (const p of before.places) if (!p.declared && !placeOf(p.name)) state.view.places.push(p);
  state.saved = snapshot();
  state.undo = [];
  state.redo = [];
  state.dirty = false;
  $("#dirty").textContent = "";
  const n = out.check.errors.length;
  notice(`saved ${out.saved} (${out.bytes} bytes)` + (n ? `, with ${n} error: ${out.check.errors[0].message}` : ""), n > 0);
  draw();
  schedule();
}

async function exportAs(to) {
  try {
    const out = await call("api/export", { graph: state.view, to });
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([out.text], { type: "text/plain" }));
    a.download = out.filename;
    a.click();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
    notice(`exported ${out.filename}`);
  } catch (err) {
    notice(`not exported: ${err.message}`, true);
  }
}

async function importFile(file) {
  const text = await file.text();
  const format = /\.(pl|db|facts)$/i.test(file.name) ? "assertions" : "toml";
  try {
    const out = await call("api/import", { text, format });
    edit((g) => {
      g.title = out.view.title; g.units = out.view.units; g.probe = out.view.probe;
      g.places = out.view.places; g.transitions = out.view.transitions;
      for (const t of g.transitions) if (t.out && !g.places.find((p) => p.name === t.out)) g.places.push({ src: null, declared: false, name: t.out });
    });
    state.layout = {};
    graphForm();
    notice(`imported ${file.name}`);
  } catch (err) {
    notice(`not imported: ${err.message}`, true);
  }
}

function sinks() {
  const used = new Set(state.view.transitions.flatMap((t) => t.in || []));
  return state.view.places.map((p) => p.name).filter((n) => !used.has(n));
}

function fullRunDialog() {
  const d = $("#fullrun-dialog");
  const f = d.querySelector("form");
  const sel = state.selected && state.selected.kind === "place" ? [state.selected.name] : sinks();
  f.outputs.value = sel.join(", ");
  $("#result-folder").textContent = state.file.replace(/\.toml$/i, "") + "-result/";
  d.returnValue = "";
  d.showModal();
  d.addEventListener("close", async () => {
    if (d.returnValue !== "run") return;
    const seed = f.seed.value.trim();
    setStatus("full run…", "computing");
    try {
      const out = await call("api/full-run", {
        outputs: f.outputs.value.split(/[,\s]+/).filter((x) => x),
        trials: Number(f.trials.value),
        seed: seed === "" ? null : Number(seed),
      });
      notice(`full run written to ${out.folder}`);
      setStatus("up to date");
      window.open(out.report, "_blank");
    } catch (err) {
      notice(`full run: ${err.message}`, true);
      setStatus("up to date");
    }
  }, { once: true });
}

// ------------------------------------------------------------------ start
function paletteButtons() {
  const types = $("#place-types");
  for (const t of state.palette.place_types) {
    const b = document.createElement("button");
    b.textContent = t;
    b.dataset.placeType = t;
    b.title = `add a ${t} place`;
    b.addEventListener("click", () => addNode("place", t));
    types.append(b);
  }
  const ops = $("#ops");
  for (const [op, info] of Object.entries(state.palette.ops)) {
    const b = document.createElement("button");
    b.textContent = op;
    b.dataset.op = op;
    b.title = info.variants.map((v) => v.doc).filter((x) => x).join("\n");
    b.addEventListener("click", () => addNode("transition", op));
    ops.append(b);
  }
}

async function start() {
  const data = await call("api/graph");
  state.file = data.file;
  state.palette = data.palette;
  state.types = data.check.types || {};
  state.errors = data.check.errors || [];
  state.warnings = data.check.warnings || [];
  setView(data.view, data.positions);
  state.saved = snapshot();
  document.title = `${data.file} — mtmc workbench`;
  $("#file").textContent = data.file + (data.exists ? "" : " (new)");
  cy = cytoscape({ container: $("#cy"), style: style(), minZoom: 0.05, maxZoom: 4 });
  window.workbench = { cy, state };
  // cytoscape caches where its container is: tell it when that changes
  new ResizeObserver(() => cy.resize()).observe($("#cy"));  // for the end-to-end tests and the console
  paletteButtons();
  graphForm();
  bindGraphForm();
  bindCanvas();
  bindKeys();
  $("#save").addEventListener("click", save);
  $("#undo").addEventListener("click", undo);
  $("#redo").addEventListener("click", redo);
  $("#delete").addEventListener("click", deleteSelected);
  $("#arcmode").addEventListener("click", () => setArcMode($("#arcmode").getAttribute("aria-pressed") !== "true"));
  $("#fullrun").addEventListener("click", fullRunDialog);
  $("#import").addEventListener("change", (e) => { if (e.target.files[0]) importFile(e.target.files[0]); e.target.value = ""; });
  $("#export").addEventListener("change", (e) => { if (e.target.value) exportAs(e.target.value); e.target.value = ""; });
  window.addEventListener("beforeunload", (e) => {
    if (state.dirty) { e.preventDefault(); e.returnValue = ""; }
  });
  draw();
  cy.fit(undefined, 30);
  drawMessages();
  inspect();
  schedule();
}

start().catch((err) => setStatus(`cannot load: ${err.message}`, "error"));
