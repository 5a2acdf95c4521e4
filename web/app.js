// Thin client: draws the frames the daemon streams over /api/ws and sends camera and light
// changes. The server keeps only the newest state (latest wins); this page acks each frame it got.
// Every pipeline, quality, terms and setting name it shows comes from GET /api/pipelines; the scene
// it shows (its JSON, camera, lights, bounds) and the scenes on offer come from the session's
// {"type": "scene"} message, so material edits and light edits start from what is on screen.
// The page's other scripts: panels.js (the side panel, loaded first) and input.js (orbit, zoom,
// drop; loaded last).
'use strict';

const $ = (id) => document.getElementById(id);
const canvas = $('view'), ctx = canvas.getContext('2d'), marker = $('marker');
const state = {
  ws: null, frames: 0, header: null, fpsFrames: 0, fpsSince: performance.now(), lastFrameAt: 0,
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
const PREFERRED = { scene: 'jade', pipeline: 'thickness', quality: 'normal' };
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

// Whether the user has picked the terms themselves (else each pipeline shows its own default).
let termsChosen = false;

// The quality, terms and bake controls follow the selected pipeline; the quality chosen before,
// and the terms if the user picked them, are kept where this pipeline has them too. Terms the
// previous pipeline imposed (thickness renders only the single term) give way to this one's
// default, so psf after thickness shows all terms, not psf's single term alone.
function pipelineChanged() {
  const p = selected();
  if (!p) return;
  $('pipeline').title = p.summary;
  const quality = $('quality').value || PREFERRED.quality, terms = $('terms').value;
  fillSelect($('quality'), p.qualities.map((q) => ({ value: q.name })),
             p.qualities.some((q) => q.name === quality) ? quality : 'normal');
  fillSelect($('terms'), p.terms.map((t) => ({ value: t })), termsChosen && p.terms.includes(terms) ? terms : p.default_terms);
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

function frameArrived(header, bitmap) {
  clearError();
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);  // reduced frames scaled up
  state.frames += 1;
  state.fpsFrames += 1;
  state.lastFrameAt = performance.now();
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
  // The rate while frames come; a still view (no frame for 1.5 s) says so instead of "0.0 fps".
  if (state.fpsFrames > 0)
    $('fps').textContent = `${(state.fpsFrames * 1000 / (now - state.fpsSince)).toFixed(1)} fps`;
  else if (!(now - state.lastFrameAt < 1500)) $('fps').textContent = 'still';
  state.fpsFrames = 0;
  state.fpsSince = now;
  const busy = state.waitingSince && now - state.waitingSince > BUSY_AFTER_MS;
  $('busy').hidden = !busy;
  if (busy) $('busy-text').textContent = `rendering ${((now - state.waitingSince) / 1000).toFixed(0)} s`;
}, 250);


$('scene').addEventListener('change', () => { state.source = null; state.medium = null; fillPipelines($('pipeline').value); pipelineChanged(); hello(false); });
$('pipeline').addEventListener('change', () => { pipelineChanged(); hello(true); });
$('quality').addEventListener('change', () => hello(true));
$('terms').addEventListener('change', () => { termsChosen = true; compositeControl(); hello(true); });
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
