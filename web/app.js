// Thin client: draws the frames the daemon streams over /api/ws and sends camera and light
// changes. The server keeps only the newest state (latest wins); this page acks each frame it got.
// Every pipeline, quality, terms and setting name it shows comes from GET /api/pipelines; the scene
// it shows (its JSON, camera, lights, bounds) and the scenes on offer come from the session's
// {"type": "scene"} message, so material edits and light edits start from what is on screen.
'use strict';

const $ = (id) => document.getElementById(id);
const canvas = $('view'), ctx = canvas.getContext('2d'), marker = $('marker');
const state = {
  ws: null, frames: 0, header: null, fpsFrames: 0, fpsSince: performance.now(),
  orbit: { yaw: 0, pitch: 0.05, radius: 4, target: [0, 0, 0], fov: 40, up: [0, 1, 0] },
  radiusRange: [1.2, 40], lights: [], revision: 0, lightRevision: 0, request: 0,
  sentAt: new Map(),  // revision key -> when the change was sent (round trip: change to its frame)
  scene: null,        // the latest {"type": "scene"} message
  source: null,       // the scene JSON the view shows (inline once the user edited it)
  baking: null, waitingSince: 0, unavailable: new Map(),
};

// The first screen: a translucent object at once, fast enough to drag: the jade bunny (a
// homogeneous medium) by `thickness`, its single-scattering glow, at exposure 2^1.6 (the slider's
// start; docs/WEB.md says why not psf or lbl).
const PREFERRED = { scene: 'jade', pipeline: 'thickness', quality: 'normal', terms: 'single' };
// A still frame of the single term adds the multiple term from one of these (the first the
// server has), at draft quality and half size: the first screen shows multiple scattering too,
// while moving frames stay fast.
const COMPOSITE = { from: ['psf', 'lbl'], quality: 'draft', scale: 0.5 };
const BUSY_AFTER_MS = 700;  // a frame not back by then shows the busy line and its cancel button
const registry = new Map();  // GET /api/pipelines: name -> {summary, terms, qualities, bakes, ...}

const add = (a, b) => a.map((x, i) => x + b[i]);
const sub = (a, b) => a.map((x, i) => x - b[i]);
const scale = (a, s) => a.map((x) => x * s);
const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => scale(a, 1 / Math.hypot(...a));
const hex = (rgb) => '#' + rgb.map((c) => Math.round(255 * Math.max(0, Math.min(1, c))).toString(16).padStart(2, '0')).join('');
const rgb = (h) => [1, 3, 5].map((i) => parseInt(h.substr(i, 2), 16) / 255);

function cameraPosition() {
  const o = state.orbit;
  return add(o.target, [o.radius * Math.sin(o.yaw) * Math.cos(o.pitch), o.radius * Math.sin(o.pitch),
                        o.radius * Math.cos(o.yaw) * Math.cos(o.pitch)]);
}
// The camera's right and up unit vectors (for moving the light in the screen's plane).
function cameraBasis() {
  const forward = norm(sub(state.orbit.target, cameraPosition()));
  const right = norm(cross(forward, [0, 1, 0]));
  return { forward, right, up: cross(right, forward) };
}

function send(msg, key) {
  if (!state.ws || state.ws.readyState !== WebSocket.OPEN) return;
  if (key) { state.sentAt.set(key, performance.now()); state.waitingSince ||= performance.now(); }
  state.ws.send(JSON.stringify(msg));
}
function sendCamera() {
  const r = ++state.revision;
  send({ type: 'camera', position: cameraPosition(), target: state.orbit.target, up: [0, 1, 0], revision: r }, 'c' + r);
  drawMarker();
}
function sendLights() {
  const r = ++state.lightRevision;
  send({ type: 'lights', lights: state.lights, revision: r }, 'l' + r);
  drawMarker();
}

const selected = () => registry.get($('pipeline').value);
function qualitySettings(p) {
  const q = p.qualities.find((q) => q.name === $('quality').value);
  return q ? q.settings : {};
}

// Replaces a select's options by items ({value, title?, disabled?}) and selects `choice` (else the
// first enabled).
function fillSelect(select, items, choice) {
  select.replaceChildren(...items.map(({ value, title, disabled }) => {
    const option = document.createElement('option');
    option.value = option.textContent = value;
    if (title) option.title = title;
    option.disabled = !!disabled;
    return option;
  }));
  const ok = items.filter((i) => !i.disabled);
  select.value = ok.some((i) => i.value === choice) ? choice : (ok[0] ? ok[0].value : '');
}

function fillPipelines(choice) {
  const scene = $('scene').value;
  fillSelect($('pipeline'), [...registry.values()].map((p) => {
    const why = state.unavailable.get(scene + '/' + p.name);
    return { value: p.name, title: why ? `not for this scene: ${why}` : p.summary, disabled: !!why };
  }), choice);
}

// The quality, terms and bake controls follow the selected pipeline; the quality and terms
// chosen before are kept where this pipeline has them too.
function pipelineChanged() {
  const p = selected();
  if (!p) return;
  $('pipeline').title = p.summary;
  const quality = $('quality').value || PREFERRED.quality, terms = $('terms').value || PREFERRED.terms;
  fillSelect($('quality'), p.qualities.map((q) => ({ value: q.name })),
             p.qualities.some((q) => q.name === quality) ? quality : 'normal');
  fillSelect($('terms'), p.terms.map((t) => ({ value: t })), p.terms.includes(terms) ? terms : p.default_terms);
  $('bake-box').hidden = !p.bakes;
  $('bake').disabled = !p.bakes || !!state.baking;
  compositeControl();
}

// The pipeline a still frame takes the multiple term from, when the selected pipeline renders
// only the single term (else none).
function compositeFrom() {
  const p = selected();
  if (!p || p.terms.includes('multiple') || $('terms').value !== 'single') return null;
  return COMPOSITE.from.map((n) => registry.get(n)).find((q) => q && q.terms.includes('multiple')) || null;
}
function compositeControl() {
  const from = compositeFrom();
  $('composite-box').hidden = !from;
  $('composite-from').textContent = from ? `(${from.name})` : '';
}

// A hello: a new scene (keep_view false) or the same view by another pipeline, quality, terms,
// exposure or material (keep_view true: the server keeps the camera and lights).
function hello(keepView) {
  const p = selected();
  if (!p) return;
  state.request += 1;
  const msg = { type: 'hello', pipeline: p.name, format: 'jpg', terms: $('terms').value,
                settings: qualitySettings(p), exposure: 2 ** Number($('exposure').value),
                request: state.request, keep_view: keepView };
  if (state.source && state.source.inline) msg.scene = state.source.json;
  else msg.scene_name = $('scene').value;
  if (state.medium && !msg.scene) msg.medium = state.medium;
  const from = compositeFrom();
  if (from && $('composite').checked) {
    const q = from.qualities.find((x) => x.name === COMPOSITE.quality);
    msg.composite = { pipeline: from.name, settings: q ? q.settings : {}, scale: COMPOSITE.scale };
  }
  send(msg, 'h' + state.request);
}

// REST calls: the token travels in the page's cookie (set when /?token=T was opened); a page
// opened with ?token= also sends it as a header.
function api(path, options = {}) {
  const token = new URLSearchParams(location.search).get('token');
  const headers = { 'Content-Type': 'application/json', ...(options.headers || {}),
                    ...(token ? { Authorization: 'Bearer ' + token } : {}) };
  return fetch(path, { ...options, headers }).then(async (r) => {
    if (options.raw && r.ok) return { status: r.status, blob: await r.blob() };
    const text = await r.text();
    let body;
    try { body = JSON.parse(text); } catch { body = { error: `${r.status} ${r.statusText}` }; }
    return { status: r.status, body };
  });
}

// Errors stay where a person looks, under the view, until the next frame comes.
function showError(text) {
  $('error').textContent = text;
  $('error').hidden = false;
}
function clearError() { $('error').hidden = true; }

// Starts (or finds) the bake job for this scene and quality, follows it, and can cancel it.
async function bake() {
  const pipeline = selected();
  if (!pipeline || !pipeline.bakes) return;
  const bar = $('bake-progress'), label = $('bake-status');
  state.baking = { id: null };
  $('bake').disabled = true;
  label.title = '';
  try {
    const body = { pipeline: pipeline.name, settings: qualitySettings(pipeline) };
    if (state.source && state.source.inline) body.scene = state.source.json; else body.scene_name = $('scene').value;
    let r = await api('/api/bakes', { method: 'POST', body: JSON.stringify(body) });
    if (r.status >= 400) throw new Error(r.body.error);
    state.baking.id = r.body.id;
    $('bake-cancel').hidden = false;
    for (;;) {
      const job = r.body;
      bar.value = job.progress;
      label.textContent = job.state === 'running' ? `${job.stage} ${(100 * job.progress).toFixed(0)}%` : job.state;
      if (job.state === 'done') {
        label.textContent = `done${job.cache_hit ? ' (cached)' : ''} · ${pipeline.name}`;
        label.title = Object.entries(job.stats || {}).map(([k, v]) => `${k} ${v}`).join(' · ');
        if ($('pipeline').value === pipeline.name) hello(true);  // the view picks the product up
        break;
      }
      if (job.state === 'failed' || job.state === 'cancelled') {
        label.textContent = job.state + (job.error ? ': ' + job.error : '');
        break;
      }
      await new Promise((ok) => setTimeout(ok, 250));
      r = await api('/api/bakes/' + state.baking.id);
      if (r.status >= 400) throw new Error(r.body.error);
    }
  } catch (e) {
    label.textContent = 'error: ' + e.message;
  } finally {
    state.baking = null;
    $('bake-cancel').hidden = true;
    $('bake').disabled = !(selected() || {}).bakes;
  }
}
function cancelBake() {
  if (state.baking && state.baking.id) api('/api/bakes/' + state.baking.id, { method: 'DELETE' });
}

// A still view is refined (docs/API.md, "Refinement"): each frame may carry its estimated error
// (relative RMSE against the reference) and how far refining got; this says both in a line.
function refineText(refine, error) {
  const e = error === undefined ? '' : `error ≈ ${(100 * error).toPrecision(2)} %`;
  if (!refine) return e;
  if (refine.state === 'converged') return `${e} · converged (under ${100 * refine.floor} %)`;
  if (refine.state === 'done') return e ? `${e} · refined` : '';
  const step = refine.stage === 'reference' ? `reference pass ${refine.pass}, ${refine.spp} spp`
    : refine.stage === 'quality' ? `quality ${refine.quality}`
    : refine.stage === 'multiple' ? `+ multiple from ${refine.pipeline}` : 'full size';
  return `${e ? e + ' · ' : ''}converging (${step})`;
}
function showRefine(refine, error) {
  $('refine').textContent = refineText(refine, error);
  $('refine-next').textContent = '';
  canvas.dataset.error = error === undefined ? '' : String(error);
  canvas.dataset.refine = refine ? refine.state : '';
  canvas.dataset.stage = refine ? refine.stage : '';
}
function showRefineNote(msg) {
  const r = msg.refine;
  if (r.state !== 'converging') return showRefine(r, msg.shown_error_estimate);
  const step = r.stage === 'reference' ? `reference pass ${r.pass}, ${r.spp} spp` : `quality ${r.quality}`;
  const e = msg.error_estimate === undefined ? '' : ` ≈ ${(100 * msg.error_estimate).toPrecision(2)} %`;
  $('refine-next').textContent = `next: ${step}${e}`;
}

// The plan: every stage, run or skipped, and why, in a list under the view.
function showPlan(plan) {
  const items = (plan && plan.stages) || [];
  $('plan').replaceChildren(...items.map((s) => {
    const li = document.createElement('li');
    li.textContent = `${s.run ? 'ran' : 'skipped'} ${s.stage}: ${s.reason}`;
    if (!s.run) li.className = 'skipped';
    return li;
  }));
  $('plan-box').querySelector('summary').textContent =
    `plan: ${plan ? plan.pipeline : ''}, ${items.filter((s) => s.run).length} stages run, ${items.filter((s) => !s.run).length} skipped`;
}

// The scene the server now shows: its camera becomes the orbit, its lights the light controls,
// its bounds the zoom's range, its medium the material controls.
function sceneArrived(msg) {
  state.scene = msg;
  const names = msg.scenes || [];
  if (names.length) {
    const current = msg.scene_name || $('scene').value;
    fillSelect($('scene'), names.map((n) => ({ value: n })), current);
    if (state.source && state.source.inline && !names.includes(current)) {
      const o = document.createElement('option');
      o.value = o.textContent = current;
      $('scene').append(o);
      $('scene').value = current;
    }
  }
  if (msg.source && !(state.source && state.source.inline)) state.source = { inline: false, json: msg.source };
  const lo = msg.bounds.min, hi = msg.bounds.max;
  const centre = scale(add(lo, hi), 0.5), r = Math.max(1e-3, Math.hypot(...sub(hi, lo)) / 2);
  const cam = msg.camera;
  if (!msg.kept_view) {
    const d = sub(cam.position, cam.target), radius = Math.hypot(...d);
    state.orbit = { ...state.orbit, target: cam.target, radius, fov: cam.fov_deg,
                    yaw: Math.atan2(d[0], d[2]), pitch: Math.asin(Math.max(-1, Math.min(1, d[1] / radius))) };
  }
  // Zoom stops outside the object's bounding sphere (around the orbit's target).
  const reach = r + Math.hypot(...sub(centre, state.orbit.target));
  state.radiusRange = [reach * 1.15, reach * 15];
  state.lights = msg.lights.map((l) => ({ ...l }));
  const image = msg.source && msg.source.image;
  // Setting a canvas's size clears it: only when it changes, so that the frame on show stays
  // until the new hello's first frame comes (a long one shows the busy line over it).
  const w = (image && image.width) || 512, h = (image && image.height) || 512;
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = marker.width = w;
    canvas.height = marker.height = h;
  }
  $('frame').style.aspectRatio = `${canvas.width} / ${canvas.height}`;
  lightControls();
  materialControls();
  drawMarker();
}

// The light controls edit the scene's first light (the one shift-drag moves); the others stay.
function lightControls() {
  const l = state.lights[0];
  $('light-index').textContent = l ? `1 of ${state.lights.length} (${l.type})` : '(none)';
  if (!l) return;
  $('light-color').value = hex(l.color);
  $('light-intensity').value = l.type === 'directional' ? l.irradiance : l.intensity;
}

// Where the first light is on screen: a ring on the marker canvas (a directional light: none).
function drawMarker() {
  const m = marker.getContext('2d');
  m.clearRect(0, 0, marker.width, marker.height);
  const l = state.lights[0];
  if (!l || !l.position) return;
  const { forward, right, up } = cameraBasis();
  const d = sub(l.position, cameraPosition()), z = dot(d, forward);
  if (z <= 0) return;
  const t = Math.tan((state.orbit.fov * Math.PI) / 360), aspect = marker.width / marker.height;
  const x = (dot(d, right) / z / (t * aspect) + 1) / 2 * marker.width;
  const y = (1 - dot(d, up) / z / t) / 2 * marker.height;
  m.strokeStyle = '#ff0'; m.lineWidth = 2;
  m.beginPath(); m.arc(x, y, 8, 0, 2 * Math.PI); m.stroke();
  m.beginPath(); m.arc(x, y, 2, 0, 2 * Math.PI); m.fillStyle = '#ff0'; m.fill();
  marker.dataset.x = x.toFixed(1);
  marker.dataset.y = y.toFixed(1);
}

const DENSITY_FIELDS = {
  constant: [['value', 1]],
  noise: [['scale', 3], ['octaves', 5], ['min', 0.2], ['max', 1], ['seed', 1]],
  layers: [['thickness', 0.25]],
  blocker: [['sigma_a', 1000]],
  grid: [],
};
// The material controls show the scene's medium: each coefficient as a colour (its channels over
// the largest) times a density (the largest channel).
function materialControls() {
  const m = (state.source && state.source.json && state.source.json.medium) || {};
  const split = (v, fallback) => {
    const c = v || fallback, k = Math.max(...c);
    return { color: hex(k > 0 ? scale(c, 1 / k) : [1, 1, 1]), k };
  };
  const s = split(m.sigma_s, [1, 1, 1]), a = split(m.sigma_a, [0.1, 0.1, 0.1]);
  $('m-scatter-color').value = s.color; $('m-scatter').value = +s.k.toPrecision(4);
  $('m-absorb-color').value = a.color; $('m-absorb').value = +a.k.toPrecision(4);
  $('m-g').value = m.g ?? 0;
  $('m-ior').value = m.ior ?? 1;
  const density = m.density || { type: 'constant' };
  const types = Object.keys(DENSITY_FIELDS);
  fillSelect($('m-density'), types.map((t) => ({ value: t, disabled: t === 'grid' && density.type !== 'grid' })), density.type);
  densityParams(density);
}
function densityParams(density) {
  const fields = DENSITY_FIELDS[$('m-density').value] || [];
  $('m-density-params').replaceChildren(...fields.map(([key, fallback]) => {
    const label = document.createElement('label');
    const input = document.createElement('input');
    input.type = 'number'; input.step = 'any'; input.dataset.key = key;
    input.value = density && density[key] !== undefined ? density[key] : fallback;
    label.append(`density ${key} `, input);
    return label;
  }));
}

// The edited material: a copy of the scene's JSON with a new medium, sent as an inline scene (the
// server keeps the view; the plan says what it rebakes).
function applyMaterial() {
  if (!state.source) return;
  const json = structuredClone(state.source.json);
  const old = json.medium || {};
  const density = $('m-density').value === (old.density || {}).type ? { ...old.density } : { type: $('m-density').value };
  if (density.type === 'blocker' && !density.shape) density.shape = { shape: 'sphere', radius: 0.4 };
  for (const input of $('m-density-params').querySelectorAll('input')) density[input.dataset.key] = Number(input.value);
  json.medium = { ...old, sigma_s: scale(rgb($('m-scatter-color').value), Number($('m-scatter').value)),
                  sigma_a: scale(rgb($('m-absorb-color').value), Number($('m-absorb').value)),
                  g: Number($('m-g').value), ior: Number($('m-ior').value), density };
  if (state.source.inline) state.source = { inline: true, json };
  else state.medium = json.medium;  // a shipped scene: the server swaps its medium
  hello(true);
}

// A dropped or chosen mesh file: uploaded (POST /api/assets), then shown in the current medium.
async function upload(file) {
  const format = file.name.split('.').pop().toLowerCase();
  $('status').textContent = `uploading ${file.name}`;
  const r = await api(`/api/assets?kind=mesh&format=${encodeURIComponent(format)}`,
                      { method: 'POST', body: file, headers: { 'Content-Type': 'application/octet-stream' } });
  if (r.status >= 400) return showError(`upload of ${file.name} failed: ${r.body.error}`);
  const json = structuredClone((state.source && state.source.json) || {});
  json.mesh = { asset: r.body.id, fit: 2 };
  if (json.medium && json.medium.density && ['blocker', 'grid'].includes(json.medium.density.type))
    json.medium.density = { type: 'constant' };
  state.source = { inline: true, json };
  state.medium = null;
  $('status').textContent = `uploaded ${file.name} (${r.body.triangles} triangles)`;
  canvas.dataset.uploaded = r.body.id;
  hello(false);
}

function download(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}
// The linear frame: the session renders the current view at full size as EXR (its "snapshot"
// message); that frame is downloaded, not drawn.
function saveExr() {
  state.snapshot = true;
  $('status').textContent = 'rendering the EXR';
  send({ type: 'snapshot' }, 'h' + state.request);
}

function frameArrived(header, bitmap) {
  clearError();
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);  // reduced frames scaled up
  state.frames += 1;
  state.fpsFrames += 1;
  $('frames').textContent = state.frames;
  // Round trip: from the change this frame answers (its camera or light revision) to now.
  const t = [state.sentAt.get('c' + header.camera_revision), state.sentAt.get('l' + header.light_revision),
             state.sentAt.get('h' + header.request)].filter((x) => x !== undefined);
  if (t.length) $('rtt').textContent = (performance.now() - Math.max(...t)).toFixed(0);
  for (const k of state.sentAt.keys()) if (performance.now() - state.sentAt.get(k) > 60000) state.sentAt.delete(k);
  $('size').textContent = `${header.width}×${header.height}${header.reduced ? ' (moving)' : ''}`;
  const composite = header.refine && header.refine.stage === 'multiple' ? `${$('pipeline').value} + multiple from ` : '';
  $('stages').textContent = `${composite}${header.pipeline}: ` + Object.entries(header.timings_ms)
    .map(([k, v]) => `${k} ${v.toFixed(1)}`).join(' · ') + ' ms';
  showRefine(header.refine, header.error_estimate);
  showPlan(header.plan);
  $('status').textContent = 'connected';
  state.waitingSince = 0;
  $('busy').hidden = true;
  canvas.dataset.frames = String(state.frames);
  canvas.dataset.revision = String(header.camera_revision);
  canvas.dataset.request = String(header.request);
  canvas.dataset.pipeline = header.pipeline;
  canvas.dataset.terms = header.plan ? header.plan.terms : '';
}

function messageArrived(msg) {
  if (msg.type === 'frame') state.header = msg;
  else if (msg.type === 'refine') showRefineNote(msg);
  else if (msg.type === 'scene' && msg.request === state.request) sceneArrived(msg);
  else if (msg.type === 'cancelled') { state.waitingSince = 0; $('status').textContent = 'cancelled: the view stays as it is'; }
  else if (msg.type === 'error' && (msg.request === undefined || msg.request === state.request)) {
    state.waitingSince = 0;
    showError(`error: ${msg.error}`);  // the message starts with the field to blame
    $('error').dataset.field = msg.field || '';
    // A pipeline that cannot render this scene (its error names it): not offered for it again;
    // the view goes back to the last pipeline that worked, else surface.
    const p = $('pipeline').value;
    if (msg.frame === undefined && msg.error.includes(`${p} pipeline`)) {
      state.unavailable.set($('scene').value + '/' + p, msg.error);
      const back = state.lastGood && state.lastGood.pipeline !== p ? state.lastGood.pipeline : 'surface';
      fillPipelines(back);
      pipelineChanged();
      hello(true);
    }
  }
}

function connect() {
  const token = new URLSearchParams(location.search).get('token');
  const scheme = location.protocol === 'https:' ? 'wss' : 'ws';
  const ws = new WebSocket(`${scheme}://${location.host}/api/ws${token ? '?token=' + encodeURIComponent(token) : ''}`);
  ws.binaryType = 'blob';
  state.ws = ws;
  ws.onopen = () => { $('status').textContent = 'connected'; hello(false); };
  ws.onclose = () => {  // the server restarted or went away: try again
    $('status').textContent = 'reconnecting';
    setTimeout(connect, 1000);
  };
  ws.onmessage = async (event) => {
    if (typeof event.data === 'string') return messageArrived(JSON.parse(event.data));
    const header = state.header;
    // Every frame is acked (the next comes only then), but a frame of an older hello (another
    // scene, pipeline or material) is not drawn.
    send({ type: 'ack', frame: header ? header.frame : 0 });
    if (!header || header.request !== state.request) return;
    if (header.format === 'exr') {
      state.snapshot = false;
      state.waitingSince = 0;
      $('status').textContent = 'connected';
      return download(event.data, `scatter-${header.pipeline}.exr`);
    }
    state.lastGood = { pipeline: header.pipeline };
    frameArrived(header, await createImageBitmap(event.data));
  };
}

// A still view sends nothing; the server closes sessions silent for --session-idle-s.
setInterval(() => send({ type: 'ping' }), 20000);
setInterval(() => {
  const now = performance.now();
  $('fps').textContent = (state.fpsFrames * 1000 / (now - state.fpsSince)).toFixed(1);
  state.fpsFrames = 0;
  state.fpsSince = now;
  const busy = state.waitingSince && now - state.waitingSince > BUSY_AFTER_MS;
  $('busy').hidden = !busy;
  if (busy) $('busy-text').textContent = `rendering ${((now - state.waitingSince) / 1000).toFixed(0)} s`;
}, 250);

// Orbit and zoom, by mouse, touch (one finger orbits, two pinch) and keyboard.
function orbitBy(dx, dy) {
  state.orbit.yaw -= dx;
  state.orbit.pitch = Math.max(-1.4, Math.min(1.4, state.orbit.pitch + dy));
  sendCamera();
}
function zoomBy(factor) {
  const [lo, hi] = state.radiusRange;
  state.orbit.radius = Math.max(lo, Math.min(hi, state.orbit.radius * factor));
  sendCamera();
}
// Shift-drag: the first light moves in the screen's plane, as far from the target as it was.
function moveLight(dx, dy) {
  const l = state.lights[0];
  if (!l || !l.position) return;
  const { right, up } = cameraBasis();
  const d = Math.hypot(...sub(l.position, state.orbit.target));
  l.position = add(l.position, add(scale(right, dx * d), scale(up, -dy * d)));
  sendLights();
}
const pointers = new Map();
canvas.addEventListener('pointerdown', (e) => {
  pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
  canvas.setPointerCapture(e.pointerId);
  canvas.focus();
});
const lift = (e) => pointers.delete(e.pointerId);
canvas.addEventListener('pointerup', lift);
canvas.addEventListener('pointercancel', lift);
canvas.addEventListener('pointermove', (e) => {
  const last = pointers.get(e.pointerId);
  if (!last) return;
  if (pointers.size === 2) {  // pinch: the fingers' distance before and after
    const [a, b] = [...pointers.values()];
    const other = a === last ? b : a;
    const before = Math.hypot(last.x - other.x, last.y - other.y);
    const after = Math.hypot(e.clientX - other.x, e.clientY - other.y);
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    if (before > 0 && after > 0) zoomBy(before / after);
    return;
  }
  const w = canvas.getBoundingClientRect().width;
  const dx = ((e.clientX - last.x) / w) * 4, dy = ((e.clientY - last.y) / w) * 4;
  pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
  if (e.shiftKey) moveLight(dx / 2, dy / 2); else orbitBy(dx, dy);
});
canvas.addEventListener('wheel', (e) => { e.preventDefault(); zoomBy(Math.exp(e.deltaY * 0.001)); }, { passive: false });
canvas.addEventListener('keydown', (e) => {
  const step = 0.08, keys = { ArrowLeft: [step, 0], ArrowRight: [-step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] };
  if (keys[e.key]) { e.preventDefault(); (e.shiftKey ? moveLight : orbitBy)(...keys[e.key].map((v) => (e.shiftKey ? -v / 2 : v))); }
  else if (e.key === '+' || e.key === '=') zoomBy(0.9);
  else if (e.key === '-') zoomBy(1.1);
});
// Drag and drop of a mesh file onto the view.
$('frame').addEventListener('dragover', (e) => { e.preventDefault(); $('drop-hint').hidden = false; });
$('frame').addEventListener('dragleave', () => { $('drop-hint').hidden = true; });
$('frame').addEventListener('drop', (e) => {
  e.preventDefault();
  $('drop-hint').hidden = true;
  if (e.dataTransfer.files[0]) upload(e.dataTransfer.files[0]);
});
$('upload').addEventListener('change', (e) => { if (e.target.files[0]) upload(e.target.files[0]); });

$('scene').addEventListener('change', () => { state.source = null; state.medium = null; fillPipelines($('pipeline').value); pipelineChanged(); hello(false); });
$('pipeline').addEventListener('change', () => { pipelineChanged(); hello(true); });
$('quality').addEventListener('change', () => hello(true));
$('terms').addEventListener('change', () => { compositeControl(); hello(true); });
$('composite').addEventListener('change', () => hello(true));
$('exposure').addEventListener('change', () => hello(true));
$('bake').addEventListener('click', bake);
$('bake-cancel').addEventListener('click', cancelBake);
$('cancel').addEventListener('click', () => send({ type: 'cancel' }));
$('m-apply').addEventListener('click', applyMaterial);
$('m-density').addEventListener('change', () => densityParams(null));
$('light-color').addEventListener('input', () => {
  if (state.lights[0]) { state.lights[0].color = rgb($('light-color').value); sendLights(); }
});
$('light-intensity').addEventListener('change', () => {
  const l = state.lights[0];
  if (!l) return;
  l[l.type === 'directional' ? 'irradiance' : 'intensity'] = Number($('light-intensity').value);
  sendLights();
});
$('save-png').addEventListener('click', () => canvas.toBlob((b) => download(b, `scatter-${$('pipeline').value}.png`), 'image/png'));
$('save-exr').addEventListener('click', saveExr);
$('fullscreen').addEventListener('click', () => {
  if (document.fullscreenElement) document.exitFullscreen(); else $('frame').requestFullscreen();
});

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
      const params = new URLSearchParams(location.search);
      fillSelect($('scene'), [{ value: params.get('scene') || PREFERRED.scene }], params.get('scene') || PREFERRED.scene);
      fillPipelines(params.get('pipeline') || PREFERRED.pipeline);
      pipelineChanged();
      clearError();
      connect();
      return;
    }
  } catch (e) {
    problem = e.message;
  }
  showError(`could not load the pipelines from the server (GET /api/pipelines): ${problem}. Trying again every 3 s.`);
  $('status').textContent = 'no pipelines';
  setTimeout(start, 3000);
}
start();
