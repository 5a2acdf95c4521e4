// Latency from a camera pose sent to its frame received, minus the server's render time (the
// server overhead: queueing, encoding, transport), over a WebSocket session.
// Usage: node --experimental-websocket bench/ws-latency.mjs URL [POSES] [SCENE] [PIPELINE] [SIZE]   e.g. ws://127.0.0.1:8080/api/ws
// SIZE: frames of SIZE x SIZE while the camera moves (the scene file, sent inline at twice that:
// moving frames are half size); without it, the shipped scene by name.
// Prints the percentiles, the stages' medians and the frames' bytes (the JPEG quality their
// headers say). Needs a global WebSocket: Node 22+, or Node 20 with --experimental-websocket.
import { readFileSync } from 'node:fs';
const [url, posesArg = '60', scene = 'bunny', pipeline = 'surface', size] = process.argv.slice(2);
const poses = Number(posesArg);
if (typeof WebSocket === 'undefined') {
  console.error('this script needs a global WebSocket: Node 22+, or node --experimental-websocket');
  process.exit(2);
}
const ws = new WebSocket(url);
ws.binaryType = 'arraybuffer';
let header = null, revision = 0, sentAt = 0;
const latency = [], overhead = [], render = [], bytes = [], stages = {};
const pose = (r) => ({ type: 'camera', position: [3.6 * Math.sin(r * 0.05), 0.2, 3.6 * Math.cos(r * 0.05)],
                       target: [0, 0, 0], revision: r });
function hello() {
  if (!size) return { type: 'hello', scene_name: scene, pipeline, format: 'jpg' };
  const inline = JSON.parse(readFileSync(new URL(`../scenes/${scene}.json`, import.meta.url), 'utf8'));
  inline.image = { width: 2 * Number(size), height: 2 * Number(size) };
  return { type: 'hello', scene: inline, pipeline, format: 'jpg' };
}
ws.onopen = () => ws.send(JSON.stringify(hello()));
ws.onmessage = (e) => {
  if (typeof e.data === 'string') { header = JSON.parse(e.data); return; }
  const now = performance.now();
  ws.send(JSON.stringify({ type: 'ack', frame: header.frame }));
  if (revision > 0 && header.camera_revision === revision) {
    const ms = Object.values(header.timings_ms).reduce((a, b) => a + b, 0);
    latency.push(now - sentAt);
    render.push(ms);
    bytes.push(e.data.byteLength);
    for (const [k, v] of Object.entries(header.timings_ms)) (stages[k] ||= []).push(v);
    overhead.push(now - sentAt - ms);
  }
  if (revision >= poses) {
    const q = (a, p) => { const s = [...a].sort((x, y) => x - y); return s[Math.min(s.length - 1, Math.floor(p * s.length))]; };
    const f = (a) => `p50 ${q(a, 0.5).toFixed(1)} ms, p95 ${q(a, 0.95).toFixed(1)} ms`;
    console.log(`${latency.length} poses, ${scene}/${pipeline}, ${header.width}x${header.height}`);
    console.log(`pose to frame:   ${f(latency)}`);
    console.log(`render (server): ${f(render)}`);
    console.log(`server overhead: ${f(overhead)}`);
    console.log(`frames/s (1 / pose to frame p50): ${(1000 / q(latency, 0.5)).toFixed(1)}`);
    console.log(`stages p50: ${Object.entries(stages).map(([k, v]) => `${k} ${q(v, 0.5).toFixed(1)}`).join(', ')} ms`);
    console.log(`image bytes p50: ${q(bytes, 0.5)} (${header.format}, quality ${header.jpeg_quality ?? 'default'})`);
    ws.close();
    return;
  }
  revision += 1;
  sentAt = performance.now();
  ws.send(JSON.stringify(pose(revision)));
};
