// pcsuite's scope page (validation/scope.py writes the data; uPlot draws). Stacked charts on one time axis,
// a mode band, zoom (drag, wheel), pan, two cursors with the mean and RMS between them by the run's own rule.
"use strict";
window.pcsuiteScope = (() => {
  const D = JSON.parse(document.getElementById("scope-data").textContent);
  const LOAD_ROWS = 4 * D.chunkRows;          // a view with at most this many rows is drawn from every row
  const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
  const CURSOR = { A: "#e6550d", B: "#3182bd" };

  function bytesOf(b64) {
    const s = atob(b64), bytes = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) bytes[i] = s.charCodeAt(i);
    return bytes;
  }
  const f64 = (b64) => new Float64Array(bytesOf(b64).buffer);      // little-endian float64
  // A chunk's samples (validation/scope.py _packed): "z8:" or "z4:", then the deflated byte planes of float64 or
  // float32 values; inflated by the browser's DecompressionStream, the planes put back together.
  async function unpack(text) {
    const width = text[1] === "4" ? 4 : 8;
    const stream = new Blob([bytesOf(text.slice(3))]).stream().pipeThrough(new DecompressionStream("deflate"));
    const planes = new Uint8Array(await new Response(stream).arrayBuffer()), n = planes.length / width;
    const bytes = new Uint8Array(planes.length);
    for (let b = 0; b < width; b++) for (let i = 0, o = b * n; i < n; i++) bytes[i * width + b] = planes[o + i];
    return width === 4 ? Float64Array.from(new Float32Array(bytes.buffer)) : new Float64Array(bytes.buffer);
  }

  // --- the data: chunks (inline, or script files loaded on demand) ---------------------------------------
  const T = D.traces.map((tr) => {
    const edgeRows = f64(tr.edges.rows), edges = new Map();
    edgeRows.forEach((r, j) => edges.set(r, j));
    const edgeValues = {};
    for (const n in tr.edges.values) edgeValues[n] = f64(tr.edges.values[n]);
    const overview = {};
    for (const n in tr.overview) overview[n] = { t: f64(tr.overview[n].t), v: f64(tr.overview[n].v) };
    return { ...tr, edges, edgeValues, overviewData: overview,
             chunkT0: tr.chunks.map((c) => c.t0), data: tr.chunks.map(() => null), pending: {} };
  });
  const waiting = {};
  const packed = D.traces.map((tr) => tr.chunks.map(() => null));   // chunks as they arrived, not yet unpacked
  window.pcsuiteChunk = (i, k, t, values) => {
    packed[i][k] = { t, values };
    const done = waiting[i + "," + k];
    if (done) { delete waiting[i + "," + k]; done(); }
  };
  async function unpackChunk(i, k) {
    const { t, values } = packed[i][k], chunk = { t: await unpack(t), v: {} };
    for (const n in values) chunk.v[n] = await unpack(values[n]);
    for (const n in T[i].same) chunk.v[n] = chunk.v[T[i].same[n]];
    packed[i][k] = null;
    T[i].data[k] = chunk;
    return chunk;
  }
  function load(i, k) {
    const tr = T[i];
    if (tr.data[k]) return Promise.resolve(tr.data[k]);
    if (!tr.pending[k]) {
      const arrived = packed[i][k] ? Promise.resolve() : new Promise((resolve, reject) => {
        waiting[i + "," + k] = resolve;
        const s = document.createElement("script");
        s.src = encodeURIComponent(D.dataDir) + "/t" + i + "-c" + k + ".js";
        s.onerror = () => reject(new Error("the scope's data file " + s.src + " could not be read"));
        document.head.appendChild(s);
      });
      tr.pending[k] = arrived.then(() => unpackChunk(i, k));
    }
    return tr.pending[k];
  }
  function upper(a, x) {          // first index with a[j] > x
    let lo = 0, hi = a.length;
    while (lo < hi) { const m = (lo + hi) >> 1; if (a[m] <= x) lo = m + 1; else hi = m; }
    return lo;
  }
  function lower(a, x) {          // first index with a[j] >= x
    let lo = 0, hi = a.length;
    while (lo < hi) { const m = (lo + hi) >> 1; if (a[m] < x) lo = m + 1; else hi = m; }
    return lo;
  }
  const chunkAt = (tr, t) => Math.max(0, Math.min(tr.chunks.length - 1, upper(tr.chunkT0, t) - 1));

  // --- what a chart shows of a window: every row, or each screen column's first, min, max and last --------
  function decimate(parts, a, b, columns) {
    let count = 0;
    for (const p of parts) count += p.hi - p.lo + 1;
    const xs = [], ys = [];
    const push = (t, v) => { xs.push(t); ys.push(Number.isNaN(v) ? null : v); };
    if (count <= 4 * columns) {
      for (const p of parts) for (let j = p.lo; j <= p.hi; j++) push(p.t[j], p.v[j]);
      return [xs, ys];
    }
    // per column its first, last, lowest and highest sample, and its first NaN (a gap): in row order
    const scale = columns / (b - a);
    let col = null, first = null, low = null, high = null, end = null, gap = null;
    const flush = () => {
      const kept = [first, low, high, end, gap].filter(Boolean).sort((x, y) => x[0] - y[0]);
      let last = -1;
      for (const [idx, t, v] of kept) if (idx !== last) { push(t, v); last = idx; }
    };
    let idx = 0;
    for (const p of parts) {
      for (let j = p.lo; j <= p.hi; j++, idx++) {
        const t = p.t[j], v = p.v[j], c = Math.floor((t - a) * scale), point = [idx, t, v];
        if (c !== col) {
          if (col !== null) flush();
          col = c; first = low = high = end = gap = null;
        }
        if (Number.isNaN(v)) { if (!gap) gap = point; continue; }
        if (!first) first = low = high = point;
        end = point;
        if (v < low[2]) low = point;
        if (v > high[2]) high = point;
      }
    }
    if (col !== null) flush();
    return [xs, ys];
  }

  let view = { min: 0, max: 1 }, full = { min: 0, max: 1 };
  let loading = false;
  function traceView(i, n, columns) {
    const tr = T[i], a = view.min, b = view.max;
    const k0 = chunkAt(tr, a), k1 = chunkAt(tr, b);
    let missing = [], rows = 0;
    for (let k = k0; k <= k1; k++) { rows += tr.chunks[k].r1 - tr.chunks[k].r0; if (!tr.data[k]) missing.push(k); }
    if (missing.length === 0) {
      const parts = [];
      for (let k = k0; k <= k1; k++) {
        const c = tr.data[k];
        let lo = Math.max(0, lower(c.t, a) - 1), hi = Math.min(c.t.length - 1, upper(c.t, b));
        if (k > k0) lo = Math.max(lo, 1);          // the row this chunk shares with the one before
        if (lo <= hi) parts.push({ t: c.t, v: c.v[n], lo, hi });
      }
      return decimate(parts, a, b, columns);
    }
    if (rows <= LOAD_ROWS && !loading) {
      loading = true;
      Promise.all(missing.map((k) => load(i, k))).then(() => { loading = false; refresh(); },
                                                           (e) => { loading = false; console.warn(e.message); });
    }
    const o = tr.overviewData[n];
    if (!o) return [[], []];
    const lo = Math.max(0, lower(o.t, a) - 1), hi = Math.min(o.t.length - 1, upper(o.t, b));
    return decimate([{ t: o.t, v: o.v, lo, hi }], a, b, columns);
  }

  // --- time and values as an engineer reads them ---------------------------------------------------------
  const TIME = D.x.name === "time";
  function timeUnit(span) {       // the time axis in the unit that suits the view; another quantity as it is
    if (!TIME) return [1, D.x.unit];
    for (const [scale, unit] of [[1e9, "ns"], [1e6, "us"], [1e3, "ms"]]) if (span * scale < 5000) return [scale, unit];
    return [1, "s"];
  }
  const xLabel = (unit) => D.x.name + (unit ? " (" + unit + ")" : "");
  function eng(v, digits = 6) {
    if (v === null || v === undefined || Number.isNaN(v)) return "-";
    if (v === 0) return "0";
    const e = Math.floor(Math.log10(Math.abs(v)) / 3) * 3, p = { "-15": "f", "-12": "p", "-9": "n", "-6": "u",
      "-3": "m", "0": "", "3": "k", "6": "M", "9": "G" }[e];
    return p === undefined ? v.toPrecision(digits) : (v / 10 ** e).toPrecision(digits) + (p ? " " + p : " ");
  }
  function parseTime(text) {
    const m = /^\s*([-+]?[0-9.]+(?:e[-+]?\d+)?)\s*(f|p|n|u|m|k)?s?\s*$/i.exec(text);
    if (!m) return NaN;
    return parseFloat(m[1]) * ({ f: 1e-15, p: 1e-12, n: 1e-9, u: 1e-6, m: 1e-3, k: 1e3 }[m[2]] || 1);
  }

  // --- charts --------------------------------------------------------------------------------------------
  const charts = [];
  let band = null;
  const cursors = { A: null, B: null };        // {t, rows: [row per trace]}
  const width = () => Math.max(400, document.getElementById("charts").clientWidth - 20);

  function drawCursors(u) {
    const ctx = u.ctx, { top, height } = u.bbox;
    for (const key of ["A", "B"]) {
      const c = cursors[key];
      if (!c) continue;
      const x = Math.round(u.valToPos(c.t, "x", true));
      if (x < u.bbox.left || x > u.bbox.left + u.bbox.width) continue;
      ctx.save(); ctx.strokeStyle = CURSOR[key]; ctx.lineWidth = 1.5 * devicePixelRatio;
      ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + height); ctx.stroke();
      ctx.fillStyle = CURSOR[key]; ctx.font = (11 * devicePixelRatio) + "px sans-serif";
      ctx.fillText(key, x + 3 * devicePixelRatio, top + 12 * devicePixelRatio); ctx.restore();
    }
  }
  // The mode band: one stripe per trace with modes (pcsuite's, then ngspice's in compare), named at its left.
  const MODES = D.modes && { ...D.modes, stripes: D.modes.stripes.map((s) => ({ ...s, t: f64(s.t), code: f64(s.code) })) };
  function drawModes(u) {
    if (!MODES) return;
    const ctx = u.ctx, { top, height } = u.bbox, h = height / MODES.stripes.length;
    MODES.stripes.forEach((m, s) => {
      const y = top + s * h, last = T[m.trace].chunks[T[m.trace].chunks.length - 1].t1;
      let j = Math.max(0, upper(m.t, view.min) - 1);
      for (; j < m.t.length && m.t[j] < view.max; j++) {
        const end = j + 1 < m.t.length ? m.t[j + 1] : last;
        const x0 = u.valToPos(Math.max(m.t[j], view.min), "x", true), x1 = u.valToPos(Math.min(end, view.max), "x", true);
        ctx.fillStyle = MODES.colours[m.code[j]];
        ctx.fillRect(x0, y, Math.max(x1 - x0, 1), h - (s + 1 < MODES.stripes.length ? devicePixelRatio : 0));
      }
      if (MODES.stripes.length > 1) {
        ctx.save(); ctx.fillStyle = "#222"; ctx.textAlign = "right"; ctx.font = (10 * devicePixelRatio) + "px sans-serif";
        ctx.fillText(m.source, u.bbox.left - 4 * devicePixelRatio, y + h / 2 + 4 * devicePixelRatio); ctx.restore();
      }
    });
  }
  function interact(u) {
    let down = null;
    u.over.addEventListener("mousedown", (e) => { down = e.clientX; });
    u.over.addEventListener("mouseup", (e) => {
      if (down !== null && Math.abs(e.clientX - down) < 3) setCursor(e.shiftKey ? "B" : "A", u.posToVal(e.offsetX, "x"));
      down = null;
    });
    u.over.addEventListener("wheel", (e) => {
      e.preventDefault();
      const c = u.posToVal(e.offsetX, "x"), f = e.deltaY > 0 ? 1.25 : 0.8;
      setView(c - (c - view.min) * f, c + (view.max - c) * f);
    }, { passive: false });
    u.over.addEventListener("dblclick", () => setView(full.min, full.max));
  }
  // One time axis: its ticks and label under the last chart (the mode band's, or the last signal's); the
  // charts above keep its grid.
  function options(label, series, height, extra, last) {
    const [, unit] = timeUnit(view.max - view.min);
    const ticks = (u, values) => { const [s] = timeUnit(view.max - view.min); return values.map((t) => +(t * s).toPrecision(8)); };
    return {
      width: width(), height, series,
      padding: [8, 24, 0, 0],              // fixed, so that every chart's plot area spans the same times
      scales: { x: { time: false, distr: D.x.log ? 3 : 1, range: () => [view.min, view.max] } },
      axes: [last ? { values: ticks, label: xLabel(unit), labelSize: 18, size: 34 }
                  : { values: (u, values) => values.map(() => ""), size: 6, ticks: { show: false } },
             { label, size: 80, labelSize: 18 }],
      cursor: { sync: { key: "pcsuite" }, drag: { x: true, y: false, setScale: false } },
      hooks: { setSelect: [(u) => {
        if (u.select.width > 2) setView(u.posToVal(u.select.left, "x"), u.posToVal(u.select.left + u.select.width, "x"));
        u.setSelect({ left: 0, top: 0, width: 0, height: 0 }, false);
      }], draw: [drawCursors, ...(extra || [])] },
      legend: { show: true },
    };
  }
  function chartData(ch) {
    const columns = Math.ceil(width());
    const tracks = ch.traces.map((i) => traceView(i, ch.name, columns));
    if (tracks.length === 1) return tracks[0];
    return uPlot.join(tracks, tracks.map(() => [1]));       // a NaN sample (null) stays a gap
  }
  function refresh() {
    for (const ch of charts) if (ch.shown) ch.u.setData(chartData(ch), true);
    if (band) band.setData([[view.min, view.max], [0, 0]], true);
    const [, unit] = timeUnit(view.max - view.min);
    const bottom = band || (charts.length && charts[charts.length - 1].u);
    if (bottom) { bottom.axes[0].label = xLabel(unit); bottom.redraw(false); }
  }
  function setView(a, b) {
    a = Math.max(full.min, a); b = Math.min(full.max, b);
    if (!(b > a)) return;
    view = { min: a, max: b };
    refresh();
  }

  // --- cursors and what lies between them ----------------------------------------------------------------
  async function rowAt(i, t) {
    const tr = T[i], k = chunkAt(tr, t), c = await load(i, k);
    let j = Math.min(c.t.length - 1, lower(c.t, t));
    if (j > 0 && Math.abs(c.t[j - 1] - t) <= Math.abs(c.t[j] - t)) j -= 1;
    return { row: tr.chunks[k].r0 + j, t: c.t[j], k, j };
  }
  async function valueAt(i, n, at) { return (await load(i, at.k)).v[n][at.j]; }
  async function integrals(i, n, ra, rb) {
    const tr = T[i], ev = tr.edgeValues[n];
    let s1 = 0, s2 = 0;
    for (let k = 0; k < tr.chunks.length; k++) {
      const c = tr.chunks[k], lo = Math.max(c.r0, ra), hi = Math.min(c.r1, rb);
      if (lo >= hi) continue;
      if (lo === c.r0 && hi === c.r1) { s1 += c.sums[n][0] ?? NaN; s2 += c.sums[n][1] ?? NaN; continue; }
      const d = await load(i, k), t = d.t, v = d.v[n];
      for (let r = lo; r < hi; r++) {
        const j = r - c.r0, dt = t[j + 1] - t[j], b = v[j + 1];
        if (tr.rule === "end") { s1 += dt * b; s2 += dt * b * b; continue; }
        const e = ev && tr.edges.get(r), a = e !== undefined && ev ? ev[e] : v[j];
        s1 += dt * (0.5 * (a + b)); s2 += dt * ((a * a + a * b + b * b) / 3);
      }
    }
    return [s1, s2];
  }
  async function setCursor(key, t) {
    if (!Number.isFinite(t)) return;
    t = Math.max(full.min, Math.min(full.max, t));
    const rows = await Promise.all(T.map((_, i) => rowAt(i, t)));
    cursors[key] = { t: rows[0].t, rows };
    document.getElementById("cursor-" + key).value = String(rows[0].t);
    for (const ch of charts) ch.u.redraw(false);
    if (band) band.redraw(false);
    await readout();
  }
  async function setCursors(a, b) { await setCursor("A", a); await setCursor("B", b); return measured(); }
  function cell(text, value, attrs) {
    const td = document.createElement("td");
    td.textContent = text;
    if (value !== undefined) td.dataset.value = String(value);
    for (const k in attrs || {}) td.dataset[k] = attrs[k];
    return td;
  }
  let results = [], generation = 0;
  async function readout() {
    const box = document.getElementById("readout"), A = cursors.A, B = cursors.B, mine = ++generation;
    const table = document.createElement("table"), head = document.createElement("tr"), rows = [];
    ["signal", "source", "at A", "at B", "B - A", "mean A..B", "RMS A..B"].forEach((h) => {
      const th = document.createElement("th"); th.textContent = h; head.appendChild(th);
    });
    table.appendChild(head);
    for (const name of D.signals) {
      const unit = D.units[name] ? " " + D.units[name] : "";
      for (let i = 0; i < T.length; i++) {
        if (!T[i].signals.includes(name)) continue;
        const row = { signal: name, source: T[i].source };
        if (A) row.a = await valueAt(i, name, A.rows[i]);
        if (B) row.b = await valueAt(i, name, B.rows[i]);
        if (A && B) {
          const [ra, rb] = [A.rows[i], B.rows[i]].sort((x, y) => x.row - y.row);
          if (rb.row > ra.row) {
            const [s1, s2] = await integrals(i, name, ra.row, rb.row), span = rb.t - ra.t;
            row.mean = s1 / span; row.rms = Math.sqrt(s2 / span);
          }
        }
        rows.push(row);
        const tr = document.createElement("tr"), q = { signal: name, source: T[i].source };
        tr.appendChild(cell(name)); tr.appendChild(cell(T[i].source));
        tr.appendChild(cell(eng(row.a) + unit, row.a, { ...q, quantity: "a" }));
        tr.appendChild(cell(eng(row.b) + unit, row.b, { ...q, quantity: "b" }));
        const diff = row.a !== undefined && row.b !== undefined ? row.b - row.a : undefined;
        tr.appendChild(cell(eng(diff) + unit, diff, { ...q, quantity: "delta" }));
        tr.appendChild(cell(eng(row.mean) + unit, row.mean, { ...q, quantity: "mean" }));
        tr.appendChild(cell(eng(row.rms) + unit, row.rms, { ...q, quantity: "rms" }));
        table.appendChild(tr);
      }
    }
    const info = document.createElement("p");
    if (A && B) {
      const dt = B.t - A.t;
      const u = D.x.unit;
      info.textContent = "A = " + eng(A.t) + u + ", B = " + eng(B.t) + u + ", B - A = " + eng(dt) + u +
        (dt !== 0 && TIME ? ", 1/(B - A) = " + eng(1 / Math.abs(dt)) + "Hz" : "");
    } else {
      info.textContent = "Click a chart to place cursor A, shift-click for cursor B (or type their times above).";
    }
    if (mine !== generation) return;          // a later cursor move started its own readout: it shows
    results = rows;
    const notes = T.filter((tr) => tr.note).map((tr) => tr.source + ": " + tr.note);
    box.replaceChildren(info, table, ...notes.map((n) => { const p = document.createElement("p"); p.className = "note"; p.textContent = n; return p; }));
  }
  const measured = () => ({ A: cursors.A && cursors.A.t, B: cursors.B && cursors.B.t, rows: results });

  // --- the page ------------------------------------------------------------------------------------------
  function controls() {
    const box = document.getElementById("controls");
    const button = (text, title, action) => {
      const b = document.createElement("button"); b.textContent = text; b.title = title; b.onclick = action; return b;
    };
    const pan = (f) => { const s = view.max - view.min; setView(view.min + f * s, view.max + f * s); };
    box.append(button("Whole run", "zoom out to the whole run (or double-click a chart)", () => setView(full.min, full.max)),
               button("\u25c0", "pan left", () => pan(-0.5)), button("\u25b6", "pan right", () => pan(0.5)));
    for (const key of ["A", "B"]) {
      const label = document.createElement("label"), input = document.createElement("input");
      label.textContent = " cursor " + key + " (" + (D.x.unit || D.x.name) + ") "; input.id = "cursor-" + key; input.size = 14;
      input.onchange = () => setCursor(key, parseTime(input.value));
      label.appendChild(input); box.appendChild(label);
    }
    const shown = document.createElement("span");
    shown.className = "toggles";
    for (const ch of charts) {
      const label = document.createElement("label"), box2 = document.createElement("input");
      box2.type = "checkbox"; box2.checked = true;
      box2.onchange = () => { ch.shown = box2.checked; ch.el.style.display = ch.shown ? "" : "none"; refresh(); };
      label.append(box2, " " + ch.name); shown.appendChild(label);
    }
    box.appendChild(shown);
  }
  async function start() {
    const t0 = performance.now();
    if (!D.dataDir) await Promise.all(T.flatMap((tr, i) => tr.chunks.map((_, k) => load(i, k))));   // inline: all
    full = { min: Math.min(...T.map((tr) => tr.chunks[0].t0)), max: Math.max(...T.map((tr) => tr.chunks[tr.chunks.length - 1].t1)) };
    view = { ...full };
    const host = document.getElementById("charts");
    for (const name of D.signals) {
      const traces = T.map((tr, i) => i).filter((i) => T[i].signals.includes(name));
      const el = document.createElement("div"); host.appendChild(el);
      const series = [{}, ...traces.map((i) => ({ label: T[i].source, stroke: COLOURS[i % COLOURS.length], width: 1, spanGaps: false }))];
      const unit = D.units[name] ? " (" + D.units[name] + ")" : "";
      const ch = { name, traces, el, shown: true };
      const last = !MODES && name === D.signals[D.signals.length - 1];
      ch.u = new uPlot(options(name + unit, series, last ? 150 : 120, [], last), [[view.min, view.max], ...traces.map(() => [null, null])], el);
      interact(ch.u);
      charts.push(ch);
    }
    if (MODES) {
      const el = document.createElement("div"); el.className = "band"; host.appendChild(el);
      const opts = options("mode", [{}, { show: false }], 100, [drawModes], true);
      opts.scales.y = { range: () => [0, 1] };
      opts.axes[1] = { show: true, label: "mode", size: 80, labelSize: 18, values: () => [] };
      opts.legend = { show: false };
      band = new uPlot(opts, [[view.min, view.max], [0, 0]], el);
      interact(band);
      const key = document.createElement("div"); key.className = "modes";
      MODES.labels.forEach((l, j) => {
        const s = document.createElement("span"); s.className = "swatch"; s.style.background = MODES.colours[j];
        key.append(s, " " + l + "  ");
      });
      host.appendChild(key);
    }
    controls();
    refresh();
    readout();
    api.openedMs = performance.now() - t0;
    api.readyAt = performance.now();       // ms since the navigation started: what opening the page took
    api.ready = true;
  }
  const api = { start, setCursor, setCursors, setView, measured, ready: false, openedMs: null, readyAt: null,
                shown: (name) => { const ch = charts.find((c) => c.name === name); return ch && [Array.from(ch.u.data[0]), Array.from(ch.u.data[1])]; },
                view: () => ({ ...view }), loading: () => loading,
                modeStripes: () => (MODES ? MODES.stripes.map((s) => s.source) : []),
                plotAreas: () => [...charts.map((c) => c.u), band].filter(Boolean).map((u) => [u.bbox.left, u.bbox.width]) };
  window.addEventListener("resize", () => { for (const ch of charts) ch.u.setSize({ width: width(), height: ch.u.height }); if (band) band.setSize({ width: width(), height: band.height }); });
  return api;
})();
