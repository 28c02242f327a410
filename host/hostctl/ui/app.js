// hostctl ui: the page's script (embedded in the hostctl binary; no libraries, no network
// access beyond its own server). Plots are drawn on canvases by hand: min/max per pixel
// column over every sample kept, which a general plotting library would not do for us, and
// nothing has to be fetched or pinned.
//
// Data: telemetry arrives as binary frames (see host/src/cmd/ui/wire.rs) and is kept in a
// ring of typed arrays; JSON messages carry config, plane, status, faults, release and tune.
'use strict';

const TOKEN = new URLSearchParams(location.search).get('token') || '';
const RING = 1 << 20; // samples kept (about 200 s at 5 kHz)
const ring = {
  seq: new Float64Array(RING), count: new Int32Array(RING), force: new Int32Array(RING),
  flags: new Uint16Array(RING), energy: new Uint32Array(RING), n: 0, // total pushed
};
const st = {
  hello: null, config: null, plane: null, status: null, faults: null, profile: null,
  paused: false, windowS: 2, viewEnd: null, nextId: 1, pending: new Map(),
  received: 0, lastSeq: -1, seqBase: null, frames: 0, fpsT: performance.now(), fps: 0,
  lagged: 0, ws: null, dirty: true,
  me: null, controller: null, running: null, // this page's client number, the controller, the operation
};
const $ = (id) => document.getElementById(id);

// ---------- connection ----------
function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(TOKEN)}`);
  ws.binaryType = 'arraybuffer';
  st.ws = ws;
  ws.onopen = () => { st.retries = 0; setConn(true); };
  ws.onclose = (ev) => {
    setConn(false);
    st.retries = (st.retries || 0) + 1;
    // The server closes with a reason (message too large, server stopped, …): show it.
    if (ev.reason) showLog(`connection closed (${ev.code}): ${ev.reason}`);
    else if (st.retries === 5) showLog('the server does not answer: what is shown is stale. If hostctl ui was restarted, open the new URL it printed (its token is new).');
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') onJson(JSON.parse(ev.data));
    else onFrame(ev.data);
  };
}
// The pill: live, not live (tune has the link) or offline (with a reload hint after a while:
// a restarted server has a new token).
function setConn(ok, why) {
  const c = $('conn');
  c.textContent = !ok ? 'offline' : (why || 'live');
  c.className = 'pill ' + (!ok ? 'bad' : (why ? 'warn' : 'ok'));
  c.dataset.state = !ok ? 'offline' : (why ? 'not-live' : 'live');
}
function send(cmd) {
  return new Promise((resolve) => {
    const id = st.nextId++;
    st.pending.set(id, resolve);
    if (!st.ws || st.ws.readyState !== 1) {
      st.pending.delete(id);
      resolve({ ok: false, error: 'not connected' });
      return;
    }
    st.ws.send(JSON.stringify(Object.assign({ id }, cmd)));
  });
}

function onFrame(buf) {
  const dv = new DataView(buf);
  if (dv.getUint32(0, true) !== 0x31545753) return;
  const chunks = dv.getUint32(4, true);
  let o = 8;
  for (let c = 0; c < chunks; c++) {
    const seq0 = dv.getUint32(o, true); const n = dv.getUint32(o + 4, true); o += 8;
    for (let i = 0; i < n; i++, o += 18) {
      let seq = seq0 + i;
      // Unwrap the 32-bit sample number.
      if (st.seqBase === null) st.seqBase = 0;
      let s = st.seqBase + seq;
      if (st.lastSeq >= 0 && s < st.lastSeq - 2147483648) { st.seqBase += 4294967296; s += 4294967296; }
      const k = ring.n % RING;
      ring.seq[k] = s;
      ring.count[k] = dv.getInt32(o + 4, true);
      ring.force[k] = dv.getInt32(o + 8, true);
      ring.flags[k] = dv.getUint16(o + 12, true);
      ring.energy[k] = dv.getUint32(o + 14, true);
      ring.n++;
      st.lastSeq = s;
    }
    st.received += n;
  }
  if (chunks > 0 && !st.paused) st.dirty = true;
  const sc = $('sample-count');
  sc.textContent = st.received.toLocaleString('en');
  sc.dataset.count = String(st.received);
}

function onJson(m) {
  switch (m.type) {
    case 'hello': onHello(m); break;
    case 'config': onConfig(m); break;
    case 'plane': st.plane = m; drawPlane(); drawFrontier(); break;
    case 'profile': onProfile(m); break;
    case 'status': onStatus(m); break;
    case 'faults': onFaults(m); break;
    case 'release': onRelease(m); break;
    case 'tune': onTune(m); break;
    case 'you': st.me = m.client; showControl(); break;
    case 'control': onControl(m); break;
    case 'op': onOp(m); break;
    case 'reply': {
      const r = st.pending.get(m.id);
      if (r) { st.pending.delete(m.id); r(m); }
      break;
    }
    case 'lagged': st.lagged += m.frames; break;
    case 'log': showLog(m.message); break;
    case 'device': if (m.error) showLog('device: ' + m.error); break;
    default: break;
  }
}

// One page controls the device; the others view until they take control (the server refuses
// their commands). The page taken over is told.
function onControl(m) {
  const was = st.controller;
  st.controller = m.controller;
  if (was === st.me && m.controller !== st.me && m.controller !== null) {
    showLog(`control was taken by page ${m.controller}: this page is now a viewer (press Take control to get it back)`);
  }
  showControl();
}
function showControl() {
  const viewer = st.me !== null && st.controller !== null && st.controller !== st.me;
  $('viewer-banner').hidden = !viewer;
  $('viewer-text').textContent = viewer ? `page ${st.controller} controls the device; this page (${st.me}) shows what it does` : '';
  document.body.dataset.role = viewer ? 'viewer' : 'controller';
  showRunning();
}
// The running long operation (release test or tune): its Run button off, its Abort on.
function onOp(m) { st.running = m.running; showRunning(); }
function showRunning() {
  const r = st.running;
  const viewer = document.body.dataset.role === 'viewer';
  $('rel-run').disabled = r !== null || viewer; $('tune-run').disabled = r !== null || viewer;
  $('rel-abort').disabled = r !== 'release' || viewer; $('tune-abort').disabled = r !== 'tune' || viewer;
  document.body.dataset.running = r || '';
  if (r === 'tune') setConn(st.ws && st.ws.readyState === 1, 'not live: tune runs');
  else setConn(st.ws && st.ws.readyState === 1);
}
function releaseSeconds() {
  const ticks = Number($('rel-ticks').value.trim());
  const el = $('rel-seconds');
  el.textContent = Number.isFinite(ticks) && ticks > 0 ? `≈ ${fmtDuration(ticks / rate())} at ${rate()} Hz` : '';
}
function fmtDuration(s) { return s < 120 ? `${s.toFixed(s < 10 ? 1 : 0)} s` : `${(s / 60).toFixed(1)} min`; }

function showLog(text) {
  const l = $('log');
  l.hidden = false;
  l.textContent = text;
}

function rate() { return st.config ? st.config.config.servo_rate_hz : (st.hello ? st.hello.device.servo_rate_hz : 1000); }

function onHello(m) {
  st.hello = m;
  $('target').textContent = m.target + ' — ' + m.device.firmware_name + ' ' + m.device.firmware_version;
  $('plane-title').textContent = `(β, σ) plane of the spring wall — ${m.target}`;
  $('kb-title').textContent = `(B, K) frontier of the spring + damper wall — ${m.target}`;
  document.querySelectorAll('.unit[data-unit]').forEach((e) => { e.textContent = m.units[e.dataset.unit] || ''; });
}
function onConfig(m) {
  st.config = m;
  st.dirty = true;
  $('cfg-text').textContent = m.text;
  const c = m.config;
  const set = (id, v) => { const e = $(id); if (document.activeElement !== e) e.placeholder = fmt(v); };
  set('cfg-stiffness', c.stiffness); set('cfg-damping', c.damping); set('cfg-force-limit', c.force_limit);
  set('cfg-max-velocity', c.max_velocity); set('cfg-energy-limit', c.energy_limit);
  $('ring-seconds').textContent = (RING / rate()).toFixed(0);
  releaseSeconds();
}
function onStatus(m) {
  st.status = m;
  $('sample-rate').textContent = Math.round(m.samples_per_s).toLocaleString('en');
  $('gaps').textContent = String(m.missing) + (st.lagged ? ` (display lagged ${st.lagged} frames)` : '');
  const r = m.recording;
  const rs = $('rec-status');
  if (r) {
    rs.className = 'msg small';
    rs.textContent = `recording ${r.file}: ${r.rows.toLocaleString('en')} rows, ${r.missing} missing, ${r.seconds.toFixed(1)} s`;
    rs.dataset.rows = String(r.rows);
  }
}
function onFaults(m) {
  st.faults = m;
  const tripped = m.latched !== 0 || m.safe_mode;
  const b = $('fault-banner');
  b.hidden = !tripped;
  const names = m.names.length ? m.names.join(', ') : 'safe mode';
  $('fault-text').textContent = `${names} (bits 0x${m.latched.toString(16)}) at tick ${m.first_tick}; the device is in safe mode until the faults are cleared.`;
  const fs = $('fault-state');
  fs.textContent = tripped ? names : 'none';
  fs.dataset.latched = String(m.latched);
}

// ---------- traces ----------
const LANES = [
  { key: 'count', label: 'position [counts]', color: '#1f5fbf' },
  { key: 'force', label: 'force', color: '#c2410c' },
  { key: 'energy', label: 'storage energy H_T/(KΔ²)', color: '#6b21a8' },
  { key: 'flags', label: 'flags / faults', color: '#374151' },
];
const FLAG_BITS = [[0, 'safe mode', '#c62828'], [1, 'hold', '#8a6d00'], [2, 'released', '#1f7a3a'], [3, 'excite', '#0e7490'], [4, 'clamped', '#b45309'], [5, 'wall off', '#6b7280']];

function fmt(v) {
  const a = Math.abs(v);
  if (v === 0) return '0';
  if (a >= 1e5 || a < 1e-3) return v.toExponential(2);
  return Number(v.toPrecision(4)).toString();
}

function drawTraces() {
  const cv = $('traces');
  const dpr = window.devicePixelRatio || 1;
  const W = Math.round(cv.clientWidth * dpr); const H = Math.round(cv.clientHeight * dpr);
  if (cv.width !== W || cv.height !== H) { cv.width = W; cv.height = H; }
  const g = cv.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  const w = cv.clientWidth; const h = cv.clientHeight;
  g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
  const left = 70; const right = 8; const pw = Math.max(10, Math.floor(w - left - right));
  const r = rate();
  const span = Math.max(2, Math.round(st.windowS * r)); // samples in the window
  const latest = st.lastSeq;
  if (!st.paused || st.viewEnd === null) st.viewEnd = latest;
  const end = st.viewEnd + 1; const start = end - span;
  // Min/max per pixel column in one pass over the kept samples inside the window.
  const cols = pw;
  const mins = LANES.map(() => new Float64Array(cols).fill(Infinity));
  const maxs = LANES.map(() => new Float64Array(cols).fill(-Infinity));
  const orFlags = new Uint16Array(cols);
  const have = Math.min(ring.n, RING);
  // Binary search the first kept sample with seq >= start.
  let lo = ring.n - have; let hi = ring.n;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (ring.seq[mid % RING] < start) lo = mid + 1; else hi = mid; }
  const fpc = st.hello ? st.hello.device.force_per_code : 1;
  let used = 0; let released = 0;
  for (let j = lo; j < ring.n; j++) {
    const k = j % RING; const s = ring.seq[k];
    if (s >= end) break;
    const c = Math.floor((s - start) * cols / span);
    const vals = [ring.count[k], ring.force[k] * fpc, ring.energy[k] / 8];
    for (let L = 0; L < 3; L++) {
      const v = vals[L];
      if (v < mins[L][c]) mins[L][c] = v;
      if (v > maxs[L][c]) maxs[L][c] = v;
    }
    orFlags[c] |= ring.flags[k];
    if (ring.flags[k] & 4) released++;
    mins[3][c] = 0; maxs[3][c] = 0;
    used++;
  }
  cv.dataset.lastSeq = String(latest);
  cv.dataset.columns = String(cols);
  cv.dataset.used = String(used);
  cv.dataset.released = String(released);
  cv.dataset.firstSeq = String(used ? ring.seq[lo % RING] : -1);
  const lh = (h - 24) / LANES.length;
  g.font = '12px DejaVu Sans, sans-serif';
  for (let L = 0; L < LANES.length; L++) {
    const y0 = 4 + L * lh; const y1 = y0 + lh - 8;
    g.strokeStyle = '#d0d4da'; g.strokeRect(left, y0, pw, y1 - y0);
    g.fillStyle = '#333'; g.fillText(LANES[L].label + (L === 1 && st.hello ? ` [${st.hello.units.force}]` : ''), left + 4, y0 + 12);
    if (L === 3) {
      const bh = (y1 - y0 - 16) / FLAG_BITS.length;
      FLAG_BITS.forEach(([bit, name, color], i) => {
        const yy = y0 + 16 + i * bh;
        g.fillStyle = '#666'; g.fillText(name, 4, yy + bh * 0.8);
        g.fillStyle = color;
        for (let c = 0; c < cols; c++) if (maxs[3][c] === 0 && (orFlags[c] >> bit) & 1) g.fillRect(left + c, yy + 1, 1, bh - 2);
      });
      continue;
    }
    if (L === 2 && st.config && !(st.config.config.stiffness > 0)) {
      // H_T/(KΔ²) is not defined without a wall: say so instead of drawing a saturated number.
      g.fillStyle = '#777'; g.fillText('wall off (K = 0): no storage energy', left + 12, (y0 + y1) / 2 + 6);
      cv.dataset.energyLane = 'wall-off';
      continue;
    }
    if (L === 2) cv.dataset.energyLane = 'drawn';
    let vmin = Infinity; let vmax = -Infinity;
    for (let c = 0; c < cols; c++) { if (mins[L][c] < vmin) vmin = mins[L][c]; if (maxs[L][c] > vmax) vmax = maxs[L][c]; }
    if (!(vmin <= vmax)) continue;
    // A flat trace is labelled with its value (a range around it would be made up).
    const flat = vmax - vmin < 1e-12; const value = vmin;
    if (flat) { vmax = value + 1; vmin = value - 1; }
    const pad = flat ? 0 : (vmax - vmin) * 0.08; vmin -= pad; vmax += pad;
    // The position lane also covers the profile's edges (walls, centres, trains, zones).
    if (L === 0) [vmin, vmax] = profileRange(vmin, vmax);
    const Y = (v) => y1 - (v - vmin) / (vmax - vmin) * (y1 - y0 - 16);
    if (L === 0) drawProfile(g, cv, left, pw, y0, y1, Y, vmin, vmax);
    g.fillStyle = '#555';
    if (flat) g.fillText(`= ${fmt(value)}`, 4, Y(value) + 4);
    else { g.fillText(fmt(vmax), 4, y0 + 20); g.fillText(fmt(vmin), 4, y1); }
    cv.dataset[`flat${L}`] = flat ? String(value) : '';
    g.strokeStyle = LANES[L].color; g.lineWidth = 1;
    g.beginPath();
    let prev = null;
    for (let c = 0; c < cols; c++) {
      if (mins[L][c] === Infinity) { prev = null; continue; }
      const x = left + c + 0.5;
      const ya = Y(maxs[L][c]); const yb = Y(mins[L][c]);
      if (prev !== null) { g.moveTo(x - 1, prev); g.lineTo(x, (ya + yb) / 2); }
      g.moveTo(x, ya); g.lineTo(x, yb + 0.5);
      prev = (ya + yb) / 2;
    }
    g.stroke();
  }
  // Time axis: device time (servo ticks / servo rate) before the newest sample shown. The
  // fast virtual device runs faster than real time: the speed-up is stated, not hidden.
  g.fillStyle = '#555';
  for (let i = 0; i <= 4; i++) {
    const x = left + pw * i / 4;
    g.fillText(`${(-(st.windowS) * (1 - i / 4)).toPrecision(3)} s`, Math.min(x, w - 50), h - 6);
  }
  const speed = st.status ? st.status.samples_per_s / r : 1;
  const fast = speed > 1.5 ? ` · device time: the virtual device runs ×${speed.toFixed(1)} real time` : '';
  cv.dataset.speed = speed.toFixed(2);
  const ch = chatter(end, r, fpc);
  cv.dataset.chatter = ch.state;
  cv.dataset.togglesPerS = ch.toggles.toFixed(1);
  $('trace-info').textContent = `${st.paused ? 'paused' : (st.running === 'tune' ? 'not live (tune has the link)' : 'live')} · ${st.windowS} s window · ${used.toLocaleString('en')} samples in ${cols} columns${fast} · ${ch.text}`;
}

// ---------- haptic profile (the `profile` message, wire.rs / profile.rs) ----------
// Drawn over the position lane, in raw counts as the lane: walls shaded beyond their
// surface, a spring's centre as a line, detent minima as thin lines over the train's span, a
// viscous zone as a light band. An element near its limit (margin < near_limit) or failing
// the check is drawn in its state's colour with a label.
const PROFILE_STYLE = {
  wall: { fill: 'rgba(100,116,139,0.22)', line: '#475569', label: 'wall (shaded: inside)' },
  spring: { line: '#0f766e', label: 'spring centre' },
  detents: { line: '#7c3aed', label: 'detent minima' },
  viscous: { fill: 'rgba(250,204,21,0.20)', line: '#ca8a04', label: 'viscous zone' },
};
const STATE_COLOR = { near: '#ea580c', fails: '#dc2626' };
function showProfile() { return st.profile && st.profile.elements.length > 0 && $('profile-show').checked; }
function profileEdges(e) {
  const g = e.geometry;
  switch (e.wire_kind) {
    case 'wall': return [g.position];
    case 'spring': return [g.center];
    case 'detents': return [g.first, g.first + (g.count - 1) * g.pitch];
    case 'viscous': return [g.from, g.to];
    default: return [];
  }
}
function profileRange(vmin, vmax) {
  if (!showProfile()) return [vmin, vmax];
  let lo = vmin; let hi = vmax;
  for (const e of st.profile.elements) for (const x of profileEdges(e)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
  if (lo === vmin && hi === vmax) return [vmin, vmax];
  const pad = (hi - lo) * 0.06;
  return [lo - pad, hi + pad];
}
function stateLabel(e) {
  if (e.state === 'fails') return 'fails';
  if (e.state === 'near') return `near limit (margin ${e.check.margin.toFixed(2)})`;
  return '';
}
function drawProfile(g, cv, left, pw, y0, y1, Y, vmin, vmax) {
  const top = y0 + 16;
  cv.dataset.profileElements = String(st.profile ? st.profile.elements.length : 0);
  if (!showProfile()) { cv.dataset.profileDrawn = '0'; cv.dataset.profileLegend = ''; cv.dataset.profileMarked = ''; return; }
  const clampY = (y) => Math.max(top, Math.min(y1, y));
  const kinds = new Set(); const marked = []; let drawn = 0;
  g.save();
  g.beginPath(); g.rect(left, top, pw, y1 - top); g.clip();
  for (const e of st.profile.elements) {
    const s = PROFILE_STYLE[e.wire_kind]; if (!s) continue;
    const mark = STATE_COLOR[e.state];
    const geo = e.geometry; let at = null; let visible = false;
    if (e.wire_kind === 'wall') {
      const ys = Y(geo.position); const yEnd = geo.side === 'upper' ? top : y1;
      visible = geo.side === 'upper' ? geo.position <= vmax : geo.position >= vmin;
      g.fillStyle = mark ? 'rgba(220,38,38,0.16)' : s.fill;
      g.fillRect(left, Math.min(ys, yEnd), pw, Math.abs(yEnd - ys));
      g.strokeStyle = mark || s.line; g.lineWidth = 1.5;
      g.beginPath(); g.moveTo(left, ys); g.lineTo(left + pw, ys); g.stroke();
      at = ys;
    } else if (e.wire_kind === 'spring') {
      const y = Y(geo.center); visible = geo.center >= vmin && geo.center <= vmax;
      g.strokeStyle = mark || s.line; g.lineWidth = 1.5; g.setLineDash([6, 3]);
      g.beginPath(); g.moveTo(left, y); g.lineTo(left + pw, y); g.stroke(); g.setLineDash([]);
      at = y;
    } else if (e.wire_kind === 'detents') {
      const j0 = Math.max(0, Math.ceil((vmin - geo.first) / geo.pitch));
      const j1 = Math.min(geo.count - 1, Math.floor((vmax - geo.first) / geo.pitch));
      visible = j1 >= j0;
      g.strokeStyle = mark || s.line; g.lineWidth = 0.75;
      // At most one line per 2 pixels: a denser train is drawn as its span.
      const px = Math.abs(Y(geo.first + geo.pitch) - Y(geo.first));
      if (visible && px < 2) {
        g.fillStyle = mark ? 'rgba(220,38,38,0.10)' : 'rgba(124,58,237,0.10)';
        const ya = Y(geo.first + j0 * geo.pitch); const yb = Y(geo.first + j1 * geo.pitch);
        g.fillRect(left, Math.min(ya, yb), pw, Math.abs(yb - ya) + 1);
      } else if (visible) {
        g.beginPath();
        for (let j = j0; j <= j1; j++) { const y = Math.round(Y(geo.first + j * geo.pitch)) + 0.5; g.moveTo(left, y); g.lineTo(left + pw, y); }
        g.stroke();
      }
      at = Y(geo.first + ((j0 + j1) / 2) * geo.pitch);
    } else if (e.wire_kind === 'viscous') {
      const ya = Y(geo.from); const yb = Y(geo.to);
      visible = geo.to >= vmin && geo.from <= vmax;
      g.fillStyle = mark ? 'rgba(220,38,38,0.12)' : s.fill;
      g.fillRect(left, Math.min(ya, yb), pw, Math.abs(yb - ya));
      at = (ya + yb) / 2;
    }
    if (!visible) continue;
    drawn++; kinds.add(e.wire_kind);
    if (mark) {
      const text = `#${e.index} ${e.kind}: ${stateLabel(e)}`;
      marked.push(text);
      g.font = 'bold 12px DejaVu Sans, sans-serif';
      const tw = g.measureText(text).width;
      const y = clampY(at) + (clampY(at) - top < 14 ? 12 : -3);
      g.fillStyle = 'rgba(255,255,255,0.85)'; g.fillRect(left + 8, y - 11, tw + 6, 14);
      g.fillStyle = mark; g.fillText(text, left + 11, y);
    }
  }
  g.restore();
  // The legend: one entry per kind drawn, and the marks in use.
  const entries = [...kinds].map((k) => [PROFILE_STYLE[k].label, PROFILE_STYLE[k].fill || null, PROFILE_STYLE[k].line]);
  for (const s8 of ['near', 'fails']) {
    if (st.profile.elements.some((e) => e.state === s8)) entries.push([s8 === 'near' ? `near limit (margin < ${st.profile.near_limit})` : 'fails the check', null, STATE_COLOR[s8]]);
  }
  g.font = '11px DejaVu Sans, sans-serif';
  const lw = Math.max(0, ...entries.map(([t]) => g.measureText(t).width)) + 30;
  const lx = left + pw - lw - 4; let ly = y0 + 4;
  if (entries.length) { g.fillStyle = 'rgba(255,255,255,0.9)'; g.fillRect(lx, ly, lw, entries.length * 14 + 4); }
  for (const [text, fill, line] of entries) {
    if (fill) { g.fillStyle = fill; g.fillRect(lx + 4, ly + 4, 16, 10); }
    g.strokeStyle = line; g.lineWidth = 1.5;
    g.beginPath(); g.moveTo(lx + 4, ly + 9); g.lineTo(lx + 20, ly + 9); g.stroke();
    g.fillStyle = '#333'; g.fillText(text, lx + 24, ly + 13);
    ly += 14;
  }
  g.font = '12px DejaVu Sans, sans-serif';
  cv.dataset.profileDrawn = String(drawn);
  cv.dataset.profileLegend = [...kinds].join(',');
  cv.dataset.profileMarked = marked.join('|');
}
function onProfile(m) {
  st.profile = m; st.dirty = true;
  const info = $('profile-info'); const table = $('profile-table'); const body = table.querySelector('tbody');
  info.dataset.source = m.elements.length ? m.source : 'none';
  info.dataset.elements = String(m.elements.length);
  if (!m.elements.length) {
    info.textContent = "no haptic profile on the device: it renders the config's wall";
    table.hidden = true; return;
  }
  const what = m.source === 'file' ? `profile "${m.name}" from ${m.file}` : "the device's active profile (not from --profile: elements numbered on the wire)";
  const chk = m.checked_against ? ` · checked against ${m.checked_against}: ${m.pass ? 'passes' : 'FAILS'}` : ' · not checked (no --tune-json): no margins';
  info.textContent = `${what}: ${m.elements.length} element${m.elements.length === 1 ? '' : 's'} over the position trace${chk}`;
  body.textContent = '';
  const num = (e, name) => { const n = e.numbers.find((x) => x.name === name); return n ? `${fmt(n.value)} ${n.unit}` : '–'; };
  for (const e of m.elements) {
    const tr = document.createElement('tr'); tr.className = e.state; tr.dataset.state = e.state;
    const span = `${e.span.lo === null ? '−∞' : e.span.lo} … ${e.span.hi === null ? '+∞' : e.span.hi}`;
    const c = e.check;
    const cells = [String(e.index), e.kind + (e.part ? ` (${e.part})` : ''), span, num(e, 'K'), num(e, 'B'),
      c && c.k_limit !== null ? `${fmt(c.k_limit)} ${m.units.k}` : '–', c && c.margin !== null ? c.margin.toFixed(2) : '–',
      e.state === 'unchecked' ? '' : (stateLabel(e) || 'ok') + (c && c.problems.length ? `: ${c.problems.join('; ')}` : '')];
    for (const t of cells) { const td = document.createElement('td'); td.textContent = t; tr.appendChild(td); }
    if (e.wire_kind === 'detents') tr.title = `${num(e, 'strength')}, pitch ${num(e, 'pitch')} (${fmt(e.geometry.pitch)} counts), ${e.geometry.count} minima`;
    body.appendChild(tr);
  }
  table.hidden = false;
}

// Chatter over the last second of device time before `end` (the rule of stiffwall_core::rest:
// more than 2 count changes is not at rest; within one count, max − min ≤ 1, it is chatter):
// toggles per second and the force's peak to peak, in the force unit and in units of c.
function chatter(end, r, fpc) {
  const span = Math.max(2, Math.round(r)); const start = end - span;
  let changes = 0; let prev = null; let nmin = Infinity; let nmax = -Infinity;
  let fmin = Infinity; let fmax = -Infinity; let n = 0;
  const have = Math.min(ring.n, RING);
  for (let j = Math.max(ring.n - have, ring.n - span - 1); j < ring.n; j++) {
    const k = j % RING; const s = ring.seq[k];
    if (s < start) continue;
    if (s >= end) break;
    const c = ring.count[k]; const f = ring.force[k] * fpc;
    if (prev !== null && c !== prev) changes++;
    prev = c; n++;
    if (c < nmin) nmin = c; if (c > nmax) nmax = c;
    if (f < fmin) fmin = f; if (f > fmax) fmax = f;
  }
  const toggles = n > 1 ? changes * r / n : 0;
  if (n < 2) return { state: 'none', toggles: 0, text: 'no samples' };
  if (changes <= 2) return { state: 'rest', toggles, text: 'at rest (≤ 2 count changes in the last second)' };
  if (nmax - nmin > 1) return { state: 'moving', toggles, text: `moving over ${nmax - nmin + 1} counts` };
  const c = st.plane && st.plane.model ? st.plane.model.coulomb : 0;
  const unit = st.hello ? st.hello.units.force : '';
  const pp = fmax - fmin;
  return { state: 'chatter', toggles, text: `CHATTER: ${toggles.toFixed(0)} toggles/s, force swing ${fmt(pp)} ${unit}${c > 0 ? ` (${(pp / c).toFixed(1)} × c)` : ''}` };
}

// ---------- (β, σ) plane ----------
const REGION_COLORS = { A: '#78c878', B: '#8caaeb', C: '#eb7878', D: '#f5be78', E: '#c8eb96', F1: '#78c878', F2: '#aadcd2' };
function drawPlane() {
  const cv = $('plane'); const g = cv.getContext('2d');
  const w = cv.width; const h = cv.height;
  g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
  const p = st.plane;
  const note = $('plane-note'); const op = $('op-point');
  if (!p) return;
  if (!p.point) {
    note.textContent = p.note || '';
    op.textContent = 'no operating point: the wall is off';
    for (const k of ['beta', 'sigma', 'k', 'px', 'py', 'region']) delete cv.dataset[k];
    // The wall is off: the regions and the device's line, drawn at a reference K, without a point.
    cv.dataset.wallOff = p.line ? '1' : '0';
    if (!p.line) return;
  } else delete cv.dataset.wallOff;
  const un = st.hello ? st.hello.units : { m: '', b: '', c: '' };
  if (p.point) note.textContent = p.model ? `model: m = ${fmt(p.model.mass)} ${un.m}, b = ${fmt(p.model.viscous)} ${un.b}, c = ${fmt(p.model.coulomb)} ${un.c} (${p.model.source}); μ = m/(KT²) = ${fmt(p.mu)}, τ_D = T_D/T = ${fmt(p.tau_d)}` : '';
  const [bmax, smax] = p.window;
  const L = 60; const B = 36; const T = 10; const R = 10;
  const X = (b) => L + b / bmax * (w - L - R);
  const Y = (s) => h - B - s / smax * (h - B - T);
  for (const poly of p.polygons) {
    g.fillStyle = REGION_COLORS[poly.region] || '#ddd';
    g.globalAlpha = 0.6;
    g.beginPath();
    poly.points.forEach(([b, s], i) => (i ? g.lineTo(X(b), Y(s)) : g.moveTo(X(b), Y(s))));
    g.closePath(); g.fill();
    g.globalAlpha = 1;
    // Label at the polygon's centroid of vertices.
    let cb = 0; let cs = 0; poly.points.forEach(([b, s]) => { cb += b; cs += s; });
    g.fillStyle = '#222'; g.font = 'bold 13px DejaVu Sans, sans-serif';
    g.fillText(poly.region, X(cb / poly.points.length) - 6, Y(cs / poly.points.length) + 4);
  }
  g.strokeStyle = '#333'; g.strokeRect(L, T, w - L - R, h - B - T);
  g.fillStyle = '#333'; g.font = '12px DejaVu Sans, sans-serif';
  g.fillText('β = b/(KT) (dimensionless viscous friction)', w / 2 - 130, h - 6);
  g.save(); g.translate(11, h / 2 + 110); g.rotate(-Math.PI / 2); g.fillText('σ = c/(KΔ) (dimensionless Coulomb friction)', 0, 0); g.restore();
  for (let i = 0; i <= 4; i++) {
    g.fillText(fmt(bmax * i / 4), X(bmax * i / 4) - 8, h - B + 14);
    g.fillText(fmt(smax * i / 4), 16, Y(smax * i / 4) + 4);
  }
  if (p.critical) {
    g.strokeStyle = '#000'; g.lineWidth = 2; g.beginPath();
    g.moveTo(X(p.critical[0][0]), Y(p.critical[0][1])); g.lineTo(X(p.critical[1][0]), Y(p.critical[1][1]));
    g.stroke(); g.lineWidth = 1;
  }
  const { beta, sigma, k } = p.point || p.line;
  // Path of the point as K grows: a ray to the origin (Fig. 4).
  const far = Math.min(bmax / Math.max(beta, 1e-300), smax / Math.max(sigma, 1e-300));
  g.strokeStyle = '#5a28a0'; g.setLineDash([5, 4]); g.beginPath();
  g.moveTo(X(0), Y(0)); g.lineTo(X(beta * far), Y(sigma * far)); g.stroke(); g.setLineDash([]);
  for (const lim of p.limits) {
    if (lim.beta > bmax || lim.sigma > smax) continue;
    const x = X(lim.beta); const y = Y(lim.sigma);
    g.strokeStyle = '#000'; g.beginPath(); g.moveTo(x - 5, y - 5); g.lineTo(x + 5, y + 5); g.moveTo(x + 5, y - 5); g.lineTo(x - 5, y + 5); g.stroke();
    g.fillStyle = '#000'; g.fillText(`${lim.label} = ${fmt(lim.k)} ${st.hello ? st.hello.units.k : ''}`, x + 7, y + 4);
  }
  if (!p.point) return;
  const px = X(Math.min(beta, bmax)); const py = Y(Math.min(sigma, smax));
  g.fillStyle = '#000'; g.beginPath(); g.arc(px, py, 6, 0, 2 * Math.PI); g.fill();
  g.fillText(`K = ${fmt(k)} ${st.hello ? st.hello.units.k : ''}`, px + 9, py - 8);
  cv.dataset.beta = String(beta); cv.dataset.sigma = String(sigma);
  cv.dataset.px = px.toFixed(1); cv.dataset.py = py.toFixed(1); cv.dataset.k = String(k);
  cv.dataset.region = p.region;
  op.textContent = `K = ${fmt(k)} ${st.hello ? st.hello.units.k : ''}: β = ${fmt(beta)}, σ = ${fmt(sigma)} — region ${p.region}: ${p.region_meaning}; critical line at ξ̇ = ${fmt(p.xidot)}`;
}

// ---------- (B, K) frontier ----------
// K_max(B) from the server (core's exact sampled linear boundary) and the configured (B, K).
function drawFrontier() {
  const cv = $('kb'); const g = cv.getContext('2d');
  const w = cv.width; const h = cv.height;
  g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
  const f = st.plane && st.plane.frontier; const info = $('kb-point');
  for (const k of ['b', 'k', 'px', 'py', 'stable']) delete cv.dataset[k];
  if (!f || !f.b) { info.textContent = f && f.note ? f.note : 'no (B, K) frontier (no device model)'; return; }
  const pt = f.point;
  const bmax = f.b_axis;
  const qc = f.quiet_ceiling > 0 ? f.quiet_ceiling : 0;
  const kmax = 1.15 * Math.max(Math.min(f.k_max_opt, 4 * Math.max(qc, pt ? pt.k : 0)), qc, pt ? pt.k : 0, 1e-300);
  const L = 60; const B = 32; const T = 10; const R = 10;
  const X = (b) => L + b / bmax * (w - L - R);
  const Y = (k) => h - B - Math.min(k, kmax) / kmax * (h - B - T);
  // Below the curve (K < K_max(B)): stable by the linear test, drawn like region A.
  g.fillStyle = REGION_COLORS.A; g.globalAlpha = 0.45; g.beginPath(); g.moveTo(X(0), Y(0));
  f.b.forEach((b, i) => g.lineTo(X(b), Y(f.k_max[i])));
  g.lineTo(X(f.b[f.b.length - 1]), Y(0)); g.closePath(); g.fill(); g.globalAlpha = 1;
  // The chatter band: stable by the linear test but above the quiet ceiling 2c/Δ, where no
  // count can hold the wall's force KΔ/2 and the count toggles for ever.
  if (qc > 0) {
    g.save(); g.beginPath(); g.moveTo(X(0), Y(0));
    f.b.forEach((b, i) => g.lineTo(X(b), Y(f.k_max[i])));
    g.lineTo(X(f.b[f.b.length - 1]), Y(0)); g.closePath(); g.clip();
    g.fillStyle = '#9660c8'; g.globalAlpha = 0.35; g.fillRect(X(0), T, w - L - R, Y(qc) - T); g.restore();
    g.strokeStyle = '#6a2c9a'; g.setLineDash([6, 4]); g.beginPath(); g.moveTo(X(0), Y(qc)); g.lineTo(w - R, Y(qc)); g.stroke(); g.setLineDash([]);
    g.fillStyle = '#6a2c9a'; g.font = '12px DejaVu Sans, sans-serif';
    g.fillText(`quiet ceiling 2c/Δ = ${fmt(qc)} ${st.hello ? st.hello.units.k : ''}: chatter band above`, X(0) + 6, Math.max(Y(qc) - 4, T + 12));
    cv.dataset.quietCeiling = String(qc);
  }
  g.strokeStyle = '#000'; g.lineWidth = 2; g.beginPath();
  f.b.forEach((b, i) => (i ? g.lineTo(X(b), Y(f.k_max[i])) : g.moveTo(X(b), Y(f.k_max[i]))));
  g.stroke(); g.lineWidth = 1;
  g.strokeStyle = '#333'; g.strokeRect(L, T, w - L - R, h - B - T);
  g.fillStyle = '#333'; g.font = '12px DejaVu Sans, sans-serif';
  const u = st.hello ? st.hello.units : { b: '', k: '' };
  g.fillText(`B, virtual damping [${u.b || ''}]`, w / 2 - 80, h - 4);
  g.save(); g.translate(11, h / 2 + 60); g.rotate(-Math.PI / 2); g.fillText(`K, stiffness [${u.k || ''}]`, 0, 0); g.restore();
  for (let i = 0; i <= 4; i++) {
    const lb = fmt(bmax * i / 4);
    g.fillText(lb, Math.min(X(bmax * i / 4) - 8, w - R - g.measureText(lb).width), h - B + 14);
    g.fillText(fmt(kmax * i / 4), 16, Y(kmax * i / 4) + 4);
  }
  const ox = X(f.b_opt); const oy = Y(f.k_max_opt);
  g.strokeStyle = '#000'; g.beginPath(); g.moveTo(ox - 5, oy - 5); g.lineTo(ox + 5, oy + 5); g.moveTo(ox + 5, oy - 5); g.lineTo(ox - 5, oy + 5); g.stroke();
  const best = `max K_max = ${fmt(f.k_max_opt)} ${u.k || ''} at B = ${fmt(f.b_opt)} ${u.b || ''}`;
  g.fillText(best, Math.min(ox + 7, w - R - g.measureText(best).width), Math.max(oy - 6, T + 12));
  if (!pt) { info.textContent = 'the wall is off: set a stiffness to see the operating point'; return; }
  const px = X(Math.min(pt.b, bmax)); const py = Y(pt.k);
  g.fillStyle = pt.stable ? '#000' : '#b71c1c'; g.beginPath(); g.arc(px, py, 6, 0, 2 * Math.PI); g.fill();
  cv.dataset.b = String(pt.b); cv.dataset.k = String(pt.k); cv.dataset.stable = String(pt.stable);
  cv.dataset.px = px.toFixed(1); cv.dataset.py = py.toFixed(1);
  cv.dataset.region = pt.region || '';
  const where = { quiet: 'below the quiet ceiling: it can come to rest', chatter: 'in the chatter band: stable, but above the quiet ceiling no count holds the wall, it toggles for ever', growth: 'above K_max(B): it grows' }[pt.region] || '';
  info.textContent = `B = ${fmt(pt.b)} ${u.b || ''}, K = ${fmt(pt.k)} ${u.k || ''}: K_max(B) = ${fmt(pt.k_max)} ${u.k || ''}, quiet ceiling ${fmt(qc)} ${u.k || ''} — ${where} (the friction-free linear loop and 2c/Δ; the (β, σ) plane has the paper's regions)`;
}

// ---------- release ----------
function onRelease(m) {
  const v = $('rel-verdict');
  if (m.state === 'running') {
    v.dataset.state = 'running';
    v.textContent = `running: release from ${m.deflection} ticks at K = ${fmt(m.stiffness)}, ${m.ticks} ticks (${fmtDuration(m.seconds)})…`;
    return;
  }
  if (m.state === 'error') { v.dataset.state = 'fail'; v.textContent = m.error; return; }
  if (m.state === 'aborted') { v.dataset.state = 'aborted'; v.textContent = m.error; return; }
  v.dataset.state = m.passes ? 'pass' : 'fail';
  v.dataset.verdict = JSON.stringify(m.verdict);
  v.textContent = `verdict: ${m.describe} (K = ${fmt(m.stiffness)}, from ${m.deflection} ticks${m.faults ? ', faults: ' + m.fault_names.join(', ') : ''})`;
  drawRelease(m);
}
function drawRelease(m) {
  const cv = $('rel-trace');
  if (cv.width !== cv.clientWidth && cv.clientWidth > 0) cv.width = cv.clientWidth;
  const g = cv.getContext('2d');
  const w = cv.width; const h = cv.height;
  g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
  // The server sends at most a few thousand points: each bucket's min and max, at their ticks.
  const t = m.trace; const c = t.counts; const n = Math.max(t.samples, 1); if (!c.length) return;
  let lo = -2; let hi = 2; for (const x of c) { if (x < lo) lo = x; if (x > hi) hi = x; }
  lo -= 0.5; hi += 1.5;
  const L = 40; const X = (i) => L + i / n * (w - L - 6); const Y = (v) => h - 18 - (v - lo) / (hi - lo) * (h - 28);
  g.strokeStyle = '#999'; g.setLineDash([6, 4]);
  for (const lv of [-1, 1]) { g.beginPath(); g.moveTo(L, Y(lv)); g.lineTo(w - 6, Y(lv)); g.stroke(); }
  g.setLineDash([]);
  g.strokeStyle = '#1f5fbf'; g.beginPath();
  c.forEach((x, k) => (k ? g.lineTo(X(t.index[k]), Y(x)) : g.moveTo(X(t.index[k]), Y(x))));
  g.stroke();
  g.fillStyle = '#333'; g.font = '12px DejaVu Sans, sans-serif';
  g.fillText(fmt(hi), 2, 14); g.fillText(fmt(lo), 2, h - 18);
  g.fillText(`x [ticks] over ${(t.samples / m.rate_hz).toFixed(2)} s after the release${c.length < t.samples ? ` (${c.length} of ${t.samples} points: min/max per bucket)` : ''}`, L + 4, h - 4);
}

// ---------- tune ----------
function onTune(m) {
  const log = $('tune-log');
  if (m.state === 'running') {
    const li = document.createElement('li'); li.textContent = m.message; log.appendChild(li);
    log.scrollTop = log.scrollHeight;
    return;
  }
  if (m.state === 'error' || m.state === 'aborted') {
    const li = document.createElement('li'); li.textContent = (m.state === 'error' ? 'failed: ' : '') + m.error; li.className = 'err'; log.appendChild(li);
    log.dataset.state = m.state;
    return;
  }
  log.dataset.state = 'done';
  const u = st.hello ? st.hello.units.k : '';
  $('tune-result').hidden = false;
  $('tune-guaranteed').textContent = `${fmt(m.guaranteed)} ${u}`;
  $('tune-expected').textContent = `${fmt(m.expected)} ${u}`;
  $('tune-verified').textContent = `${fmt(m.verified)} ${u} (${m.trials.length} release tests)`;
  const wall = m.damping > 0 ? `, B = ${fmt(m.damping)} (${m.damper})` : '';
  const rest = m.rests ? 'comes to rest in every test' : `CHATTERS: ${m.no_rest || 'chatter accepted'}`;
  $('tune-set').textContent = `${fmt(m.set)} ${u}${wall} ${m.saved ? '(set and saved)' : '(dry run: not set)'}; ${rest}; quiet ceiling 2c/Δ ${fmt(m.quiet_ceiling)}`;
  $('tune-set').dataset.rests = String(m.rests);
  for (const t of m.trials) {
    const li = document.createElement('li');
    li.textContent = `release at K = ${fmt(t.k)}: ${typeof t.verdict === 'string' ? t.verdict : JSON.stringify(t.verdict)}`;
    log.appendChild(li);
  }
}

// ---------- map viewer ----------
const CLASS_COLORS = { growing: '#282828', persistent: '#787878', non_monotone_decay: '#c8c8c8', monotone_decay: '#ffffff' };
async function openMap(file) {
  const msg = $('map-msg');
  msg.className = 'msg small'; msg.textContent = `reading ${file.name}…`;
  const text = await file.text();
  const r = await fetch(`/api/map?token=${encodeURIComponent(TOKEN)}`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: text });
  const m = await r.json();
  if (!r.ok) { msg.className = 'msg small err'; msg.textContent = m.error; return; }
  msg.className = 'msg small ok';
  msg.textContent = `${file.name}: μ = ${JSON.stringify(m.mu)}, τ_D = ${JSON.stringify(m.tau_d)}, ${m.periods} periods, ${m.panels.length} panel(s). Dark: growing, grey: persistent, light: non-monotone decay, white: monotone decay; red: analytic boundaries.`;
  drawMap(m);
}
function drawMap(m) {
  const cv = $('map-canvas'); cv.hidden = false;
  const n = m.panels.length; const cols = Math.min(n, 3); const rows = Math.ceil(n / cols);
  const pw = 330; const ph = 300;
  cv.width = cols * pw; cv.height = rows * ph;
  const g = cv.getContext('2d'); g.fillStyle = '#fff'; g.fillRect(0, 0, cv.width, cv.height);
  const [b0, b1, s0, s1] = m.window; const [db, ds] = m.cell;
  m.panels.forEach((p, i) => {
    const ox = (i % cols) * pw; const oy = Math.floor(i / cols) * ph;
    const L = ox + 56; const T = oy + 20; const W = pw - 70; const H = ph - 50;
    const X = (b) => L + (b - b0) / (b1 - b0) * W; const Y = (s) => T + H - (s - s0) / (s1 - s0) * H;
    for (const [b, s, c] of p.points) {
      g.fillStyle = CLASS_COLORS[c] || '#f0f';
      g.fillRect(X(b - db / 2), Y(s + ds / 2), Math.ceil(X(b + db / 2) - X(b - db / 2)) + 0.5, Math.ceil(Y(s - ds / 2) - Y(s + ds / 2)) + 0.5);
    }
    g.save(); g.beginPath(); g.rect(L, T, W, H); g.clip();
    g.strokeStyle = '#e00'; g.lineWidth = 2;
    for (const [[xa, ya], [xb, yb]] of p.lines) { g.beginPath(); g.moveTo(X(xa), Y(ya)); g.lineTo(X(xb), Y(yb)); g.stroke(); }
    g.restore();
    g.strokeStyle = '#333'; g.lineWidth = 1; g.strokeRect(L, T, W, H);
    g.fillStyle = '#333'; g.font = '12px DejaVu Sans, sans-serif';
    g.fillText(`μ = ${fmt(p.mu)}, τ_D = ${fmt(p.tau_d)}, ξ̇0 = ${p.xidot0} ticks/period`, L + 4, oy + 14);
    g.fillText(fmt(b0), L - 4, T + H + 14); g.fillText(fmt(b1), L + W - 36, T + H + 14); g.fillText('β = b/(KT)', L + W / 2 - 30, T + H + 26);
    g.fillText(fmt(s1), ox + 2, T + 10); g.fillText(fmt(s0), ox + 2, T + H); g.save(); g.translate(ox + 44, T + H / 2 + 30); g.rotate(-Math.PI / 2); g.fillText('σ = c/(KΔ)', 0, 0); g.restore();
  });
  cv.dataset.panels = String(n);
}

// ---------- controls ----------
// Commands are typed: a number field takes a JSON number. Text that is not a finite number
// is sent as it is, and the server refuses it naming the field.
function num(text) { const x = Number(text); return text !== '' && Number.isFinite(x) ? x : text; }
function flash(el, ok, text) { el.className = 'msg ' + (ok ? 'ok' : 'err'); el.textContent = text; }

$('cfg-form').addEventListener('submit', async (e) => {
  e.preventDefault();
  const set = {};
  for (const el of $('cfg-form').querySelectorAll('input, select')) {
    const v = el.value.trim();
    if (v !== '') set[el.name] = el.tagName === 'SELECT' ? v : num(v);
  }
  const r = await send({ cmd: 'config', set });
  flash($('cfg-msg'), r.ok, r.ok ? 'applied' : r.error);
  if (r.ok) for (const el of $('cfg-form').querySelectorAll('input')) el.value = '';
});
$('clear-faults').onclick = $('banner-clear').onclick = async () => {
  const r = await send({ cmd: 'clear_faults' });
  if (!r.ok) showLog(r.error);
};
$('rel-run').onclick = async () => {
  const args = { deflection: num($('rel-deflection').value.trim()), ticks: num($('rel-ticks').value.trim()) };
  const k = $('rel-stiffness').value.trim(); if (k !== '') args.stiffness = num(k);
  const v = $('rel-verdict'); v.dataset.state = 'running'; v.textContent = 'starting…';
  const r = await send({ cmd: 'release', args });
  if (!r.ok && v.dataset.state !== 'aborted') { v.dataset.state = 'fail'; v.textContent = r.error; }
};
$('rel-ticks').addEventListener('input', releaseSeconds);
$('rel-abort').onclick = $('tune-abort').onclick = async () => {
  const r = await send({ cmd: 'abort' });
  if (!r.ok) showLog(r.error);
};
$('take-control').onclick = async () => {
  const r = await send({ cmd: 'take_control' });
  if (!r.ok) showLog(r.error);
};
$('tune-run').onclick = async () => {
  const args = { margin: num($('tune-margin').value.trim()), 'dry-run': $('tune-dry-run').checked };
  const mv = $('tune-max-velocity').value.trim(); if (mv !== '') args['max-velocity'] = num(mv);
  $('tune-log').textContent = ''; $('tune-result').hidden = true;
  const r = await send({ cmd: 'tune', args });
  if (!r.ok && !/tune failed|tune aborted/.test(r.error)) onTune({ state: 'error', error: r.error });
};
$('rec-start').onclick = async () => {
  const r = await send({ cmd: 'record_start', file: $('rec-file').value.trim() });
  flash($('rec-status'), r.ok, r.ok ? `recording to ${r.result.file}` : r.error);
};
$('rec-stop').onclick = async () => {
  const r = await send({ cmd: 'record_stop' });
  flash($('rec-status'), r.ok, r.ok ? `${r.result.file}: ${r.result.rows} rows; ${r.result.stats.missing} missing` : r.error);
  if (r.ok) $('rec-status').dataset.rows = String(r.result.rows);
};
$('xidot-apply').onclick = async () => {
  const r = await send({ cmd: 'velocity', xidot: Number($('xidot').value) });
  if (!r.ok) $('plane-note').textContent = r.error;
};
$('map-file').addEventListener('change', (e) => { if (e.target.files[0]) openMap(e.target.files[0]); });
$('pause').onclick = () => {
  st.paused = !st.paused;
  st.dirty = true;
  $('pause').textContent = st.paused ? 'Resume' : 'Pause';
};
$('profile-show').onchange = () => { st.dirty = true; };
$('window').onchange = (e) => { st.windowS = Number(e.target.value); st.dirty = true; };
function zoom(f) {
  st.windowS = Math.min(200, Math.max(0.005, st.windowS * f));
  st.dirty = true;
}
$('zoom-in').onclick = () => zoom(0.5);
$('zoom-out').onclick = () => zoom(2);
$('traces').addEventListener('wheel', (e) => { e.preventDefault(); zoom(e.deltaY > 0 ? 1.25 : 0.8); }, { passive: false });
let drag = null;
$('traces').addEventListener('mousedown', (e) => { if (st.paused) drag = { x: e.clientX, end: st.viewEnd }; });
window.addEventListener('mouseup', () => { drag = null; });
window.addEventListener('mousemove', (e) => {
  if (!drag) return;
  const cv = $('traces'); const span = st.windowS * rate();
  st.viewEnd = Math.min(st.lastSeq, drag.end - (e.clientX - drag.x) * span / (cv.clientWidth - 78));
  st.dirty = true;
});

// Redraw when something changed (new samples while live, or the view), at most once per
// display frame: at 5 kHz that is one redraw per telemetry frame (40 per second).
function frame(t) {
  if (st.dirty) {
    st.dirty = false;
    drawTraces();
    st.frames++;
  }
  if (t - st.fpsT >= 1000) {
    st.fps = st.frames * 1000 / (t - st.fpsT); st.frames = 0; st.fpsT = t;
    $('fps').textContent = st.fps.toFixed(0); $('fps').dataset.fps = st.fps.toFixed(1);
  }
  requestAnimationFrame(frame);
}
window.addEventListener('resize', () => { st.dirty = true; });
connect();
requestAnimationFrame(frame);
