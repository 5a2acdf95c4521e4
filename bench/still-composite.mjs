// The still frames of a live session whose hello asks for a composite (docs/API.md): the full
// frame of the single term, then the one with the multiple term added, timed from the hello (the
// first: the multiple pipeline's light volume is made) and from a camera-only change after it
// (kept). Prints each frame's stage, size, bytes and stage times.
// With OUT=DIR it writes each frame there (DIR/PHASE-STAGE.FORMAT; FORMAT=png or jpg, the default),
// at the web client's exposure, 2^1.6.
// Usage: node --experimental-websocket bench/still-composite.mjs URL [SCENE] [PIPELINE] [FROM] [SCALE]
//   e.g. ws://127.0.0.1:8080/api/ws jade thickness psf 0.5
import { writeFileSync } from 'node:fs';
const [url, scene = 'jade', pipeline = 'thickness', from = 'psf', scaleArg = '0.5'] = process.argv.slice(2);
if (typeof WebSocket === 'undefined') {
  console.error('this script needs a global WebSocket: Node 22+, or node --experimental-websocket');
  process.exit(2);
}
const registry = await (await fetch(url.replace(/^ws/, 'http').replace('/api/ws', '/api/pipelines'))).json();
const draft = (registry.pipelines.find((p) => p.name === from).qualities.find((q) => q.name === 'draft') || {}).settings || {};
const ws = new WebSocket(url);
ws.binaryType = 'arraybuffer';
let header = null, since = 0, phase = 'hello';
ws.onopen = () => {
  since = performance.now();
  ws.send(JSON.stringify({ type: 'hello', scene_name: scene, pipeline, terms: 'single', format: process.env.FORMAT || 'jpg', exposure: 2 ** 1.6,
                           composite: { pipeline: from, settings: draft, scale: Number(scaleArg) } }));
};
ws.onmessage = (e) => {
  if (typeof e.data === 'string') {
    const m = JSON.parse(e.data);
    if (m.type === 'frame') header = m;
    else if (m.type === 'error') { console.error(m.error); process.exit(1); }
    return;
  }
  ws.send(JSON.stringify({ type: 'ack', frame: header.frame }));
  const stage = header.refine ? header.refine.stage : (header.reduced ? 'moving' : '?');
  const ms = Object.entries(header.timings_ms).map(([k, v]) => `${k} ${v.toFixed(0)}`).join(', ');
  console.log(`${phase}: ${stage} ${header.width}x${header.height} after ${(performance.now() - since).toFixed(0)} ms, ` +
              `${e.data.byteLength} bytes (q ${header.jpeg_quality}); ${header.pipeline}: ${ms}`);
  if (process.env.OUT) writeFileSync(`${process.env.OUT}/${phase}-${stage}.${header.format}`, Buffer.from(e.data));
  if (stage !== 'multiple') return;
  if (phase === 'camera') { ws.close(); return; }
  phase = 'camera';
  since = performance.now();
  ws.send(JSON.stringify({ type: 'camera', position: [1.2, 0.4, 3.4], target: [0, 0, 0], revision: 1 }));
};
