// tactile_web's page: draws each update of tactile_web's event stream (/stream). What it shows
// is also written into the DOM as text and data-* attributes, which the browser test reads.
// ?freeze=SEQUENCE holds the view at the first update where every fingertip has reached that
// frame sequence, and closes the stream.
'use strict';

const params = new URLSearchParams(window.location.search);
const freezeAt = params.has('freeze') ? Number(params.get('freeze')) : null;
const kHistory = 300;   // points per rolling plot
const kEventsShown = 200;
const svgNs = 'http://www.w3.org/2000/svg';
// The paper's SEARCH and MOVE are the controller's finger modes; the wire carries the phase, so
// the page shows the mode each phase runs in (docs/control.md).
const kSearchPhases = ['GRASP', 'TWIST_GRASP'];
const kMovePhases = ['APPROACH', 'DESCEND', 'LIFT', 'TRANSPORT', 'LOWER', 'RETRACT'];

const domes = new Map();  // fingertip id -> {root, elements: [...]}
let eventsSeen = 0;
let received = 0;
let windowStart = performance.now();
let windowCount = 0;
let perSecond = 0;
let frozen = false;
// Shear arrows: one element spacing long for the largest shear seen so far (at least 5 mN), a
// scale that only grows, so that arrows stay comparable over a run; the legend says the scale.
let shearFullN = 0.005;

function fmt(v, digits) { return Number(v).toFixed(digits); }

function setFlag(el, on, alarm) {
  el.className = 'flag ' + (on ? 'on' : 'off') + (alarm ? ' alarm' : '');
  el.dataset.on = on ? '1' : '0';
}

function makeChart(id, title, unit) {
  const colours = { left: '#1565c0', right: '#ef6c00' };
  return {
    colours,
    chart: new Chart(document.getElementById(id), {
      type: 'line',
      data: { datasets: [] },
      options: {
        animation: false, responsive: true, maintainAspectRatio: false, parsing: false,
        normalized: true, spanGaps: true,
        elements: { point: { radius: 0 }, line: { borderWidth: 1.5 } },
        scales: { x: { type: 'linear', title: { display: true, text: 's' } },
                  y: { beginAtZero: true, title: { display: true, text: unit } } },
        plugins: { title: { display: true, text: title }, legend: { position: 'right' } },
      },
    }),
  };
}

const forceChart = typeof Chart === 'undefined' ? null
  : makeChart('force-chart', 'max F_z per fingertip', 'N');
const slipChart = typeof Chart === 'undefined' ? null
  : makeChart('slip-chart', 'max displacement per frame (grey: dr, the paper rule)', 'mm');
let t0 = null;

function push(plot, label, x, y, colour) {
  if (!plot) return;
  let ds = plot.chart.data.datasets.find((d) => d.label === label);
  if (!ds) {
    ds = { label, data: [], borderColor: colour, backgroundColor: colour };
    plot.chart.data.datasets.push(ds);
  }
  ds.data.push({ x, y });
  if (ds.data.length > kHistory) ds.data.splice(0, ds.data.length - kHistory);
}

function threshold(plot, label, x, y) { push(plot, label, x, y, '#9e9e9e'); }

// One point of the rolling charts: an update, or one of the points tactile_web kept of the
// updates before this page joined (the 'history' event: same names).
let chartPoints = 0;
function plotPoint(p) {
  if (t0 === null) t0 = p.time_ns;
  const x = (p.time_ns - t0) / 1e9;
  for (const f of p.fingertips) {
    const c = forceChart ? forceChart.colours[f.id] || '#6a1b9a' : '';
    push(forceChart, f.id, x, f.max_fz_n, c);
    push(slipChart, f.id, x, f.max_slip_mm, c);
  }
  threshold(forceChart, 'F2', x, p.f2_n);
  threshold(slipChart, 'dr', x, p.dr_mm);
  ++chartPoints;
  document.getElementById('side').dataset.chartPoints = String(chartPoints);
}

function redrawCharts() {
  if (forceChart) forceChart.chart.update('none');
  if (slipChart) slipChart.chart.update('none');
}

function dome(f) {
  let d = domes.get(f.id);
  if (d && d.elements.length === f.elements.length) return d;
  const root = document.createElement('div');
  root.className = 'fingertip';
  root.id = 'fingertip-' + f.id;
  root.innerHTML = '<h2></h2><div class="flags"></div><div class="summary"></div>';
  root.querySelector('h2').textContent = f.id;
  const flags = root.querySelector('.flags');
  const flagEls = {};
  for (const name of ['TOUCH', 'SLIP', 'OVER']) {
    const s = document.createElement('span');
    s.id = 'flag-' + f.id + '-' + name;
    s.textContent = name;
    flags.appendChild(s);
    flagEls[name] = s;
    setFlag(s, false, false);
  }
  // The element positions fill a 100 x 100 view, y down as in the image.
  let minx = Infinity, maxx = -Infinity, miny = Infinity, maxy = -Infinity;
  for (const e of f.elements) {
    minx = Math.min(minx, e.x); maxx = Math.max(maxx, e.x);
    miny = Math.min(miny, e.y); maxy = Math.max(maxy, e.y);
  }
  const span = Math.max(maxx - minx, maxy - miny, 1e-9);
  const scale = 76 / span;
  const svg = document.createElementNS(svgNs, 'svg');
  svg.setAttribute('viewBox', '0 0 100 100');
  svg.setAttribute('class', 'dome');
  const defs = document.createElementNS(svgNs, 'defs');
  defs.innerHTML = '<marker id="head-' + f.id + '" viewBox="0 0 6 6" refX="5" refY="3" ' +
    'markerWidth="4" markerHeight="4" orient="auto"><path d="M0,0 L6,3 L0,6 z" ' +
    'fill="#1a237e"/></marker>';
  svg.appendChild(defs);
  const elements = [];
  const spacing = f.elements.length > 1 ? 76 / Math.sqrt(f.elements.length) : 20;
  for (const e of f.elements) {
    const g = document.createElementNS(svgNs, 'g');
    g.id = 'element-' + f.id + '-' + e.id;
    const cx = 50 + (e.x - (minx + maxx) / 2) * scale;
    const cy = 50 + (e.y - (miny + maxy) / 2) * scale;
    const c = document.createElementNS(svgNs, 'circle');
    c.setAttribute('cx', fmt(cx, 2));
    c.setAttribute('cy', fmt(cy, 2));
    const line = document.createElementNS(svgNs, 'line');
    line.setAttribute('class', 'shear');
    line.setAttribute('marker-end', 'url(#head-' + f.id + ')');
    const title = document.createElementNS(svgNs, 'title');
    const label = document.createElementNS(svgNs, 'text');
    label.setAttribute('x', fmt(cx, 2));
    label.setAttribute('y', fmt(cy + spacing * 0.52, 2));
    label.textContent = String(e.id);
    g.append(c, line, title, label);
    svg.appendChild(g);
    elements.push({ g, c, line, title, cx, cy });
  }
  root.appendChild(svg);
  if (d) d.root.replaceWith(root);
  d = { root, elements, flagEls, summary: root.querySelector('.summary'), spacing };
  domes.set(f.id, d);
  const box = document.getElementById('fingertips');
  box.querySelector('.hint')?.remove();
  // left on the left and right on the right, whatever order their frames came in
  const order = (id) => (id === 'left' ? '0' : id === 'right' ? '2' : '1' + id);
  const sorted = [...domes.keys()].sort((a, b) => (order(a) < order(b) ? -1 : 1));
  for (const id of sorted) box.appendChild(domes.get(id).root);
  return d;
}

function colour(ratio) {
  if (ratio > 1) return '#b71c1c';
  const hue = 120 - 120 * Math.max(0, ratio);  // green to red as F_z nears F2
  return 'hsl(' + fmt(hue, 0) + ',75%,45%)';
}

function drawFingertip(f, s) {
  const d = dome(f);
  d.root.dataset.sequence = String(f.sequence);
  d.root.dataset.decided = f.decided ? '1' : '0';
  setFlag(d.flagEls.TOUCH, f.touch, false);
  setFlag(d.flagEls.SLIP, f.slip, true);
  setFlag(d.flagEls.OVER, f.over, true);
  d.summary.textContent = (f.decided ? '' : 'no decision \u00b7 ') +
    'seq ' + f.sequence + ' \u00b7 ' + fmt(f.fps, 0) + ' fps \u00b7 ' +
    f.status + (f.lost ? ' \u00b7 lost ' + f.lost : '') +
    (f.age_s > 1 ? ' \u00b7 stale ' + fmt(f.age_s, 0) + ' s' : '') +
    ' \u00b7 max F_z ' + fmt(f.max_fz_n, 2) + ' N \u00b7 max d ' + fmt(f.max_slip_mm, 4) + ' mm';
  const rMax = d.spacing * 0.48;
  for (let i = 0; i < f.elements.length; ++i) {
    const e = f.elements[i];
    const v = d.elements[i];
    const ratio = e.fz / s.f2_n;
    const r = e.contact ? Math.max(rMax * 0.25, rMax * Math.sqrt(Math.min(ratio, 1.2))) : rMax * 0.15;
    v.c.setAttribute('r', fmt(r, 2));
    v.c.setAttribute('class', 'element' + (e.contact ? '' : ' nocontact') + (e.slip ? ' slip' : ''));
    v.c.setAttribute('fill', e.contact ? colour(ratio) : '#bdbdbd');
    const sx = e.fx / shearFullN * d.spacing;
    const sy = e.fy / shearFullN * d.spacing;
    const shown = e.contact && Math.hypot(sx, sy) > 0.3;
    v.line.setAttribute('x1', fmt(v.cx, 2));
    v.line.setAttribute('y1', fmt(v.cy, 2));
    v.line.setAttribute('x2', fmt(v.cx + (shown ? sx : 0), 2));
    v.line.setAttribute('y2', fmt(v.cy + (shown ? sy : 0), 2));
    v.line.setAttribute('visibility', shown ? 'visible' : 'hidden');
    v.g.dataset.contact = e.contact ? '1' : '0';
    v.g.dataset.slip = e.slip ? '1' : '0';
    v.g.dataset.fz = String(e.fz);
    v.g.dataset.fx = String(e.fx);
    v.g.dataset.fy = String(e.fy);
    v.title.textContent = f.id + ' e' + e.id + ': ' +
      (e.contact ? 'F_z ' + fmt(e.fz, 3) + ' N, F_x ' + fmt(e.fx, 3) + ' N, F_y ' + fmt(e.fy, 3) + ' N'
                 : 'no contact') + (e.slip ? ', slipping' : '');
  }
}

function addEvents(s) {
  const fresh = Math.min(s.events_total - eventsSeen, s.events.length);
  const list = document.getElementById('events');
  for (const e of s.events.slice(s.events.length - fresh)) {
    const li = document.createElement('li');
    const t = new Date(e.time_ns / 1e6).toISOString().substring(11, 23);
    li.textContent = t + ' ' + e.kind + (e.detail ? ' ' + e.detail : '');
    list.insertBefore(li, list.firstChild);
  }
  while (list.childElementCount > kEventsShown) list.removeChild(list.lastChild);
  eventsSeen = s.events_total;
  list.dataset.total = String(s.events_total);
}

function draw(s) {
  document.getElementById('phase').textContent = s.phase;
  document.getElementById('cycle').textContent = s.cycle > 0 ? 'twist cycle ' + s.cycle : '';
  setFlag(document.getElementById('flag-SEARCH'), kSearchPhases.includes(s.phase), false);
  setFlag(document.getElementById('flag-MOVE'), kMovePhases.includes(s.phase), false);
  for (const f of s.fingertips) {
    for (const e of f.elements) {
      if (e.contact) shearFullN = Math.max(shearFullN, Math.hypot(e.fx, e.fy));
    }
  }
  document.getElementById('shear-scale').textContent = fmt(shearFullN * 1000, 1) + ' mN';
  const by = document.getElementById('flags-by');
  by.textContent = s.flags_label;
  by.dataset.from = s.flags_from;
  by.dataset.detector = s.detector;
  by.className = 'box' + (s.flags_from === 'none' ? ' warn' : '');
  for (const f of s.fingertips) drawFingertip(f, s);
  addEvents(s);
  plotPoint(s);
  redrawCharts();
  ++received;
  ++windowCount;
  const now = performance.now();
  if (now - windowStart >= 1000) {
    perSecond = windowCount * 1000 / (now - windowStart);
    windowCount = 0;
    windowStart = now;
  }
  const counters = document.getElementById('counters');
  counters.textContent = 'updates received ' + received + ' (' + fmt(perSecond, 1) + '/s), ' +
    'server update ' + s.update + ', coalesced ' + s.coalesced + ', messages ' + s.messages +
    (s.undecodable ? ', undecodable ' + s.undecodable : '');
  counters.dataset.received = String(received);
}

function reached(s) {
  return freezeAt !== null && s.fingertips.length > 0 &&
    s.fingertips.every((f) => f.sequence >= freezeAt);
}

const status = document.getElementById('status');
const stream = new EventSource('stream');
stream.onopen = () => { if (!frozen) { status.textContent = 'live'; status.className = 'status live'; } };
stream.onerror = () => {
  if (frozen) return;
  status.textContent = 'connection lost, retrying';
  status.className = 'status lost';
};
stream.addEventListener('end', () => {
  stream.close();
  if (frozen) return;
  status.textContent = 'tactile_web stopped';
  status.className = 'status lost';
  document.body.dataset.ended = '1';
});
stream.addEventListener('history', (m) => {
  if (frozen) return;
  for (const p of JSON.parse(m.data)) plotPoint(p);
  redrawCharts();
});
stream.onmessage = (m) => {
  if (frozen) return;
  const s = JSON.parse(m.data);
  draw(s);
  if (reached(s)) {
    frozen = true;
    stream.close();
    const held = s.fingertips.map((f) => f.id + ' ' + f.sequence).join(', ');
    const box = document.getElementById('frozen');
    box.textContent = 'frozen at ' + held;
    box.classList.remove('hidden');
    status.textContent = 'frozen';
    status.className = 'status frozen';
    document.body.dataset.frozen = held;
  }
};
