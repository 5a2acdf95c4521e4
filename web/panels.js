// The side panel and the overlay's lines (loaded before app.js, whose state and helpers these
// use when called): bake progress and cancel, the refinement line, the plan, the light and
// material controls, the light's marker, mesh upload, saving PNG and EXR.
'use strict';

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
  // Framed whole: the fitted mesh lies in a box of side 2 about the origin (a bounding sphere of
  // radius at most sqrt 3), seen along the current camera's direction.
  const cam = json.camera || {};
  const fov = cam.fov_deg || 40, from = cam.position || [0, 0, 1];
  const len = Math.hypot(...from) || 1, dist = 1.1 * Math.sqrt(3) / Math.sin((fov * Math.PI) / 360);
  json.camera = { ...cam, position: from.map((v) => (v / len) * dist), target: [0, 0, 0] };
  if (json.medium && json.medium.density && ['blocker', 'grid'].includes(json.medium.density.type))
    json.medium.density = { type: 'constant' };
  state.source = { inline: true, json };
  state.medium = null;
  $('status').textContent = `uploaded ${file.name} (${r.body.triangles} triangles)`;
  canvas.dataset.uploaded = r.body.id;
  hello(false);
}

// A density grid file (nx ny nz float32 values, x fastest, the sides from #grid-dims): uploaded
// (POST /api/assets?kind=grid) over the object's bounds, then the current medium's density.
async function uploadGrid(file) {
  const dims = $('grid-dims').value.split(',').map((v) => Number(v.trim()));
  if (dims.length !== 3 || !dims.every((n) => Number.isInteger(n) && n >= 1 && n <= 512))
    return showError(`grid dims: "${$('grid-dims').value}" must be three integers in [1, 512], nx,ny,nz`);
  const expected = dims[0] * dims[1] * dims[2] * 4;
  if (file.size !== expected)
    return showError(`upload of ${file.name}: ${file.size} bytes, but ${dims.join(' x ')} float32 values are ${expected}`);
  const b = state.scene && state.scene.bounds;
  if (!b) return showError('upload of a grid: no scene is shown yet');
  const bounds = [...b.min, ...b.max].join(',');
  $('status').textContent = `uploading ${file.name}`;
  const r = await api(`/api/assets?kind=grid&dims=${dims.join(',')}&bounds=${bounds}`,
                      { method: 'POST', body: file, headers: { 'Content-Type': 'application/octet-stream' } });
  if (r.status >= 400) return showError(`upload of ${file.name} failed: ${r.body.error}`);
  const density = { type: 'grid', asset: r.body.id };
  const json = structuredClone((state.source && state.source.json) || {});
  json.medium = { ...(json.medium || {}), density };
  if (state.source && state.source.inline) state.source = { inline: true, json };
  else state.medium = json.medium;  // a shipped scene: the server swaps its medium
  $('status').textContent = `uploaded ${file.name} (${dims.join(' x ')} grid)`;
  canvas.dataset.uploadedGrid = r.body.id;
  hello(true);
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
