// Frame times of the lbl pipeline in a live session: a light change (march + diffusion with warm
// start + view) against a camera-only change (view only), per stage, from the server's timings.
// While messages come the server renders at half size; once still it refines at full size, which
// for lbl is a view pass alone. So each change yields a half-size frame (the change's work) and a
// full-size one (the view at the scene's size).
// Usage: node --experimental-websocket bench/lbl-frames.mjs URL [CHANGES] [SCENE] [TERMS] [SETTINGS_JSON]
const [url, changesArg = '8', scene = 'sphere', terms = 'all', settingsArg = '{}'] = process.argv.slice(2);
const changes = Number(changesArg);
if (typeof WebSocket === 'undefined') {
  console.error('this script needs a global WebSocket: Node 22+, or node --experimental-websocket');
  process.exit(2);
}
const ws = new WebSocket(url);
ws.binaryType = 'arraybuffer';
const rec = { light: [], lightFull: [], camera: [], cameraFull: [] };
let header = null, step = 0, kind = 'hello', reducedSeen = null;
const light = (r) => {
  const a = r * 5 * Math.PI / 180;  // the point light turns 5 degrees about y per change
  return { type: 'lights', revision: r,
           lights: [{ type: 'point', position: [3 * Math.cos(a) + 3 * Math.sin(a), 3, 3 * Math.cos(a) - 3 * Math.sin(a)],
                      color: [1, 1, 1], intensity: 20 }] };
};
const camera = (r) => ({ type: 'camera', revision: r, target: [0, 0, 0],
                         position: [4 * Math.sin(r * 0.1), 0.2, 4 * Math.cos(r * 0.1)] });
const next = () => {
  if (kind === 'camera' && step >= changes) return finish();
  step += kind === 'camera' || kind === 'hello' ? 1 : 0;
  kind = kind === 'light' ? 'camera' : 'light';
  reducedSeen = null;
  ws.send(JSON.stringify(kind === 'light' ? light(step) : camera(step)));
};
ws.onopen = () => ws.send(JSON.stringify({ type: 'hello', scene_name: scene, pipeline: 'lbl', terms, format: 'png',
                                           settings: JSON.parse(settingsArg) }));
ws.onmessage = (e) => {
  if (typeof e.data === 'string') {
    header = JSON.parse(e.data);
    if (header.type === 'error') { console.error(header.error); process.exit(1); }
    return;
  }
  ws.send(JSON.stringify({ type: 'ack', frame: header.frame }));
  const rev = kind === 'light' ? header.light_revision : header.camera_revision;
  if (kind === 'hello') { if (!header.reduced) next(); return; }
  if (rev !== step) return;
  if (header.reduced) { reducedSeen = header; return; }
  if (reducedSeen) {
    rec[kind].push(reducedSeen);
    rec[kind + 'Full'].push(header);
  }
  next();
};
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s.length ? s[Math.floor(s.length / 2)] : NaN; };
const stage = (frames, name) => median(frames.map((f) => f.timings_ms[name] ?? 0));
const total = (frames) => median(frames.map((f) => Object.values(f.timings_ms).reduce((a, b) => a + b, 0)));
const steps = (frames) => median(frames.map((f) => {
  const d = f.plan.stages.find((s) => s.name === 'diffuse' || s.stage === 'diffuse');
  const m = d && /in (\d+) steps/.exec(d.reason);
  return m ? Number(m[1]) : 0;
}));
function finish() {
  const L = rec.light, LF = rec.lightFull, C = rec.camera, CF = rec.cameraFull;
  const w = (f) => f.length ? `${f[0].width}x${f[0].height}` : '-';
  console.log(`lbl ${scene} terms ${terms}, ${L.length} light and ${C.length} camera changes (medians, ms)`);
  console.log(`light change  (${w(L)}): march ${stage(L, 'march').toFixed(1)}, second ${stage(L, 'second').toFixed(1)}, ` +
              `diffuse ${stage(L, 'diffuse').toFixed(1)} ` +
              `(${steps(L)} steps, warm), view ${stage(L, 'view').toFixed(1)}, total ${total(L).toFixed(1)}`);
  console.log(`camera change (${w(C)}): view ${stage(C, 'view').toFixed(1)}, total ${total(C).toFixed(1)}`);
  console.log(`still frame   (${w(CF)}): view ${stage(CF, 'view').toFixed(1)}, total ${total(CF).toFixed(1)}`);
  console.log(`light change at ${w(CF)}: march + second + diffuse + view = ` +
              `${(stage(L, 'march') + stage(L, 'second') + stage(L, 'diffuse') + stage(CF, 'view')).toFixed(1)}`);
  ws.close();
}
