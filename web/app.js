// Thin client: draws the frames the daemon streams over /api/ws and sends camera and light
// changes. The server keeps only the newest state (latest wins); this page acks each frame it drew.
'use strict';

const canvas = document.getElementById('view');
const ctx = canvas.getContext('2d');
const $ = (id) => document.getElementById(id);
const state = {
  ws: null, frames: 0, header: null, sentAt: 0, fpsFrames: 0, fpsSince: performance.now(),
  orbit: { yaw: 0, pitch: 0.05, radius: 3.6 }, light: [2, 3, 3], revision: 0, lightRevision: 0,
  baking: false,
};

function cameraMessage() {
  const o = state.orbit;
  const position = [o.radius * Math.sin(o.yaw) * Math.cos(o.pitch), o.radius * Math.sin(o.pitch),
                    o.radius * Math.cos(o.yaw) * Math.cos(o.pitch)];
  return { type: 'camera', position, target: [0, 0, 0], up: [0, 1, 0], revision: ++state.revision };
}

function lightsMessage() {
  const hex = $('light-color').value;
  const color = [1, 3, 5].map((i) => parseInt(hex.substr(i, 2), 16) / 255);
  return { type: 'lights', revision: ++state.lightRevision,
           lights: [{ type: 'point', position: state.light, color, intensity: Number($('light-intensity').value) }] };
}

function send(msg, timed = true) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) {
    if (timed) state.sentAt = performance.now();  // round trip: from a change to its frame
    state.ws.send(JSON.stringify(msg));
  }
}

// The pipeline menu starts on this one when the server offers it, else on the server's first.
const PREFERRED_PIPELINE = 'surface';
// The quality the menu starts on when the pipeline offers it (each pipeline's own defaults).
const PREFERRED_QUALITY = 'normal';
// The server's registry (GET /api/pipelines): name -> {summary, terms, default_terms, bakes,
// qualities, ...}. Every pipeline, quality, terms and setting name the page shows comes from it.
const registry = new Map();

const selected = () => registry.get($('pipeline').value);
function qualitySettings(pipeline) {
  const q = pipeline.qualities.find((q) => q.name === $('quality').value);
  return q ? q.settings : {};
}

// Replaces a select's options by items ({value, title?}) and selects `choice` (else the first).
function fillSelect(select, items, choice) {
  select.replaceChildren(...items.map(({ value, title }) => {
    const option = document.createElement('option');
    option.value = option.textContent = value;
    if (title) option.title = title;
    return option;
  }));
  select.value = items.some((i) => i.value === choice) ? choice : (items[0] ? items[0].value : '');
}

// The quality, terms and bake controls follow the selected pipeline. The quality chosen before
// is kept where this pipeline has it too; the terms start at the pipeline's default.
function pipelineChanged() {
  const p = selected();
  $('pipeline').title = p.summary;
  const before = $('quality').value;
  fillSelect($('quality'), p.qualities.map((q) => ({ value: q.name })),
             p.qualities.some((q) => q.name === before) ? before : PREFERRED_QUALITY);
  fillSelect($('terms'), p.terms.map((t) => ({ value: t })), p.default_terms);
  $('bake-box').hidden = !p.bakes;
  $('bake').disabled = !p.bakes || state.baking;
}

function hello() {
  const p = selected();
  if (!p) return;
  send({ type: 'hello', scene_name: $('scene').value, pipeline: p.name, format: 'jpg',
         terms: $('terms').value, settings: qualitySettings(p) });
}

// REST calls carry the page's token, if it was opened with ?token=.
function api(path, options = {}) {
  const token = new URLSearchParams(location.search).get('token');
  const headers = { 'Content-Type': 'application/json', ...(token ? { Authorization: 'Bearer ' + token } : {}) };
  return fetch(path, { ...options, headers }).then(async (r) => {
    const text = await r.text();
    let body;
    try { body = JSON.parse(text); } catch { body = { error: `${r.status} ${r.statusText}` }; }
    return { status: r.status, body };
  });
}

// Starts (or finds) the bake job for this scene and quality and follows it to the end.
async function bake() {
  const pipeline = selected();
  if (!pipeline || !pipeline.bakes) return;
  state.baking = true;
  $('bake').disabled = true;
  const bar = $('bake-progress'), label = $('bake-status');
  label.title = '';
  try {
    let r = await api('/api/bakes', { method: 'POST', body: JSON.stringify(
      { scene_name: $('scene').value, pipeline: pipeline.name, settings: qualitySettings(pipeline) }) });
    if (r.status >= 400) throw new Error(r.body.error);
    const id = r.body.id;
    for (;;) {
      const job = r.body;
      bar.value = job.progress;
      label.textContent = job.state === 'running' ? `${job.stage} ${(100 * job.progress).toFixed(0)}%` : job.state;
      if (job.state === 'done') {
        label.textContent = `done${job.cache_hit ? ' (cached)' : ''} · ${pipeline.name}`;
        // What the product holds, as the pipeline reports it, in the tooltip.
        label.title = Object.entries(job.stats || {}).map(([k, v]) => `${k} ${v}`).join(' · ');
        if ($('pipeline').value === pipeline.name) hello();  // the view picks the product up
        break;
      }
      if (job.state === 'failed' || job.state === 'cancelled') {
        label.textContent = job.state + (job.error ? ': ' + job.error : '');
        break;
      }
      await new Promise((ok) => setTimeout(ok, 250));
      r = await api('/api/bakes/' + id);
      if (r.status >= 400) throw new Error(r.body.error);
    }
  } catch (e) {
    label.textContent = 'error: ' + e.message;
  } finally {
    state.baking = false;
    $('bake').disabled = !(selected() || {}).bakes;
  }
}

// A still view is refined (docs/API.md, "Refinement"): each frame may carry its estimated error
// (relative RMSE against the reference) and how far refining got; this says both in a line.
function refineText(refine, error) {
  const e = error === undefined ? '' : `error ≈ ${(100 * error).toPrecision(2)} %`;
  if (!refine) return e;
  if (refine.state === 'converged') return `${e} · converged (under ${100 * refine.floor} %)`;
  if (refine.state === 'done') return e ? `${e} · refined` : '';
  const step = refine.stage === 'reference' ? `reference pass ${refine.pass}, ${refine.spp} spp`
    : refine.stage === 'quality' ? `quality ${refine.quality}` : 'full size';
  return `${e ? e + ' · ' : ''}converging (${step})`;
}

function showRefine(refine, error) {
  $('refine').textContent = refineText(refine, error);
  $('refine-next').textContent = '';
  canvas.dataset.error = error === undefined ? '' : String(error);
  canvas.dataset.refine = refine ? refine.state : '';
}

// A refinement step the server did not send (not a tenth better than the frame on show): how far
// it got, under the line; or, once refinement ended there, the line's new state.
function showRefineNote(msg) {
  const r = msg.refine;
  if (r.state !== 'converging') return showRefine(r, msg.shown_error_estimate);
  const step = r.stage === 'reference' ? `reference pass ${r.pass}, ${r.spp} spp` : `quality ${r.quality}`;
  const e = msg.error_estimate === undefined ? '' : ` ≈ ${(100 * msg.error_estimate).toPrecision(2)} %`;
  $('refine-next').textContent = `next: ${step}${e}`;
}

function connect() {
  const token = new URLSearchParams(location.search).get('token');
  const url = `ws://${location.host}/api/ws${token ? '?token=' + encodeURIComponent(token) : ''}`;
  const ws = new WebSocket(url);
  ws.binaryType = 'blob';
  state.ws = ws;
  ws.onopen = () => { $('status').textContent = 'connected'; hello(); };
  ws.onclose = () => {  // the server restarted or went away: try again
    $('status').textContent = 'reconnecting';
    setTimeout(connect, 1000);
  };
  ws.onmessage = async (event) => {
    if (typeof event.data === 'string') {
      const msg = JSON.parse(event.data);
      if (msg.type === 'error') $('status').textContent = 'error: ' + msg.error;
      else if (msg.type === 'frame') state.header = msg;
      else if (msg.type === 'refine') showRefineNote(msg);
      return;
    }
    const header = state.header;
    const bitmap = await createImageBitmap(event.data);
    canvas.width = bitmap.width;
    canvas.height = bitmap.height;
    ctx.drawImage(bitmap, 0, 0);
    state.frames += 1;
    state.fpsFrames += 1;
    $('frames').textContent = state.frames;
    $('rtt').textContent = (performance.now() - state.sentAt).toFixed(0);
    $('stages').textContent = header ? `${header.pipeline}: ` + Object.entries(header.timings_ms)
      .map(([k, v]) => `${k} ${v.toFixed(1)}`).join(' · ') + ' ms' : '';
    if (header) showRefine(header.refine, header.error_estimate);
    $('status').textContent = 'connected';
    canvas.dataset.frames = String(state.frames);
    canvas.dataset.revision = header ? String(header.camera_revision) : '0';
    send({ type: 'ack', frame: header ? header.frame : 0 }, false);
  };
}

// A still view sends nothing; the server closes sessions silent for --session-idle-s.
setInterval(() => send({ type: 'ping' }, false), 20000);

setInterval(() => {
  const now = performance.now();
  $('fps').textContent = (state.fpsFrames * 1000 / (now - state.fpsSince)).toFixed(1);
  state.fpsFrames = 0;
  state.fpsSince = now;
}, 1000);

let drag = null;
canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('pointermove', (e) => {
  if (!drag) return;
  const dx = (e.clientX - drag.x) * 0.01, dy = (e.clientY - drag.y) * 0.01;
  drag = { x: e.clientX, y: e.clientY };
  if (e.shiftKey) {
    state.light = [state.light[0] + dx * 3, state.light[1] - dy * 3, state.light[2]];
    send(lightsMessage());
  } else {
    state.orbit.yaw -= dx;
    state.orbit.pitch = Math.max(-1.4, Math.min(1.4, state.orbit.pitch + dy));
    send(cameraMessage());
  }
});
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  state.orbit.radius = Math.max(1.2, Math.min(20, state.orbit.radius * Math.exp(e.deltaY * 0.001)));
  send(cameraMessage());
}, { passive: false });
$('scene').addEventListener('change', hello);
$('pipeline').addEventListener('change', () => { pipelineChanged(); hello(); });
$('quality').addEventListener('change', hello);
$('terms').addEventListener('change', hello);
$('bake').addEventListener('click', bake);
$('light-color').addEventListener('input', () => send(lightsMessage()));
$('light-intensity').addEventListener('input', () => send(lightsMessage()));

// The menus come from the server's registry; until it answers there is nothing to ask for, so the
// page says why and tries again (the daemon may be restarting, or the token may be wrong).
async function start() {
  let problem;
  try {
    const r = await api('/api/pipelines');
    const list = r.body && Array.isArray(r.body.pipelines) ? r.body.pipelines : null;
    if (r.status >= 400) problem = (r.body && r.body.error) || `${r.status}`;
    else if (!list || list.length === 0) problem = 'the answer lists no pipelines';
    else {
      registry.clear();
      for (const p of list) registry.set(p.name, p);
      fillSelect($('pipeline'), list.map((p) => ({ value: p.name, title: p.summary })),
                 registry.has(PREFERRED_PIPELINE) ? PREFERRED_PIPELINE : list[0].name);
      pipelineChanged();
      $('error').hidden = true;
      connect();
      return;
    }
  } catch (e) {
    problem = e.message;
  }
  $('error').textContent = `could not load the pipelines from the server (GET /api/pipelines): ${problem}. ` +
                           'Trying again every 3 s.';
  $('error').hidden = false;
  $('status').textContent = 'no pipelines';
  setTimeout(start, 3000);
}
start();
