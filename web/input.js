// Input on the view (loaded after app.js): orbit and zoom by mouse, touch (one finger orbits, two
// pinch) and keyboard, shift-drag for the light, drag and drop of a mesh file.
'use strict';

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
$('upload-grid').addEventListener('change', (e) => { if (e.target.files[0]) uploadGrid(e.target.files[0]); });
