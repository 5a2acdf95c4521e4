// The web client on a phone's terms, in Debian's chromium through playwright-core (as
// client.test.mjs). Screenshots go to OUT_DIR. Run by CTest: node --test touch.test.mjs.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { colourOf, frameAfter, frames, launch, recordSocket, startDaemon } from './page_helpers.mjs';

// Touch: one finger orbits, two fingers pinch the zoom (real touch events through the DevTools
// protocol, so the page's pointer handling is what a phone gives it). A mesh dropped on the view
// is uploaded and shown. A long frame shows the busy line after 0.7 s; its cancel button stops it.
test('touch and pinch, drag and drop, the busy line\'s cancel', { timeout: 200000 }, async () => {
  const { proc, url } = await startDaemon(['--refine-max-passes', '0'], 'touch');
  const browser = await launch();
  const out = process.env.OUT_DIR || '.';
  mkdirSync(out, { recursive: true });
  try {
    const page = await browser.newPage({ viewport: { width: 600, height: 900 }, hasTouch: true, isMobile: true });
    const sock = recordSocket(page);
    await page.goto(url);
    await frameAfter(page, 0);
    await page.waitForTimeout(500);  // the scene message: the orbit and the zoom's range
    const box = await page.locator('#view').boundingBox();
    const cdp = await page.context().newCDPSession(page);
    const touch = (type, points) => cdp.send('Input.dispatchTouchEvent', {
      type, touchPoints: points.map(([x, y], id) => ({ x: box.x + x, y: box.y + y, id })) });
    const distance = (m) => Math.hypot(...m.position.map((v, i) => v - m.target[i]));

    // One finger: orbit (camera poses at the same distance, the position moving).
    let k = sock.sent.length;
    await touch('touchStart', [[100, 150]]);
    for (let i = 1; i <= 5; ++i) await touch('touchMove', [[100 + 20 * i, 150]]);
    await touch('touchEnd', []);
    const orbit = sock.sent.slice(k).filter((m) => m.type === 'camera');
    assert.ok(orbit.length >= 3, `a one-finger drag sent camera poses: ${orbit.length}`);
    assert.ok(Math.abs(distance(orbit.at(-1)) - distance(orbit[0])) < 1e-6, 'orbiting keeps the distance');
    assert.notDeepEqual(orbit.at(-1).position, orbit[0].position, 'the camera moved round');

    // Two fingers moving apart: zoom in (the camera comes nearer the target).
    await page.waitForTimeout(300);
    k = sock.sent.length;
    const before = distance(orbit.at(-1));
    await touch('touchStart', [[120, 150], [180, 150]]);
    for (let i = 1; i <= 5; ++i) await touch('touchMove', [[120 - 10 * i, 150], [180 + 10 * i, 150]]);
    await touch('touchEnd', []);
    const pinch = sock.sent.slice(k).filter((m) => m.type === 'camera');
    assert.ok(pinch.length >= 1, 'a pinch sent camera poses');
    assert.ok(distance(pinch.at(-1)) < 0.8 * before,
              `spreading two fingers zoomed in: ${before.toFixed(3)} -> ${distance(pinch.at(-1)).toFixed(3)}`);
    await page.screenshot({ path: `${out}/browser-touch.png` });

    // Drag and drop of a mesh file on the view: the hint shows while it hovers; the drop uploads
    // it (POST /api/assets) and the view shows it.
    const cube = ['v -0.6 -0.6 -0.6', 'v 0.6 -0.6 -0.6', 'v 0.6 0.6 -0.6', 'v -0.6 0.6 -0.6',
                  'v -0.6 -0.6 0.6', 'v 0.6 -0.6 0.6', 'v 0.6 0.6 0.6', 'v -0.6 0.6 0.6',
                  'f 1 3 2', 'f 1 4 3', 'f 5 6 7', 'f 5 7 8', 'f 1 2 6', 'f 1 6 5',
                  'f 2 3 7', 'f 2 7 6', 'f 3 4 8', 'f 3 8 7', 'f 4 1 5', 'f 4 5 8'].join('\n') + '\n';
    const dt = await page.evaluateHandle((text) => {
      const d = new DataTransfer();
      d.items.add(new File([text], 'dropped-cube.obj', { type: 'text/plain' }));
      return d;
    }, cube);
    await page.dispatchEvent('#frame', 'dragover', { dataTransfer: dt });
    assert.equal(await page.isVisible('#drop-hint'), true, 'the drop hint shows while a file hovers');
    const uploaded = page.waitForResponse((r) => r.url().includes('/api/assets') && r.request().method() === 'POST');
    const h = sock.sent.length, n = await frames(page);
    await page.dispatchEvent('#frame', 'drop', { dataTransfer: dt });
    assert.equal((await uploaded).status(), 201);
    assert.equal(await page.isVisible('#drop-hint'), false);
    const dropped = await sock.next(sock.sent, h, (m) => m.type === 'hello');
    assert.ok(dropped.scene && dropped.scene.mesh.asset, `the hello shows the dropped mesh: ${JSON.stringify(dropped.scene && dropped.scene.mesh)}`);
    await page.waitForFunction((r) => document.getElementById('view').dataset.request === String(r), dropped.request, { timeout: 60000 });
    assert.ok(await frames(page) > n);
    assert.match(await page.textContent('#status'), /dropped-cube\.obj|connected/);
    await page.screenshot({ path: `${out}/browser-dropped.png` });

    // A long frame (the path tracer, all terms, on the sphere at full size): the busy line and its
    // cancel button show; the cancel stops the frame, the line goes, and the page says so.
    await page.selectOption('#scene', 'sphere');
    await frameAfter(page, await frames(page));
    k = sock.received.length;
    await page.selectOption('#pipeline', 'reference');
    await page.selectOption('#terms', 'all');
    await page.waitForSelector('#busy', { state: 'visible', timeout: 30000 });
    const shown = await colourOf(page);
    assert.ok(shown.n > 1000, `the last frame stays on show while the new one renders: ${shown.n} pixels`);
    assert.match(await page.textContent('#busy-text'), /rendering \d+ s/);
    await page.screenshot({ path: `${out}/browser-busy.png` });
    await page.click('#cancel');
    const cancelled = await sock.next(sock.received, k, (m) => m.type === 'cancelled');
    assert.equal(cancelled.frame_cancelled, true, 'the frame in flight was stopped');
    await page.waitForSelector('#busy', { state: 'hidden', timeout: 5000 });
    assert.match(await page.textContent('#status'), /cancelled/);
    await page.close();
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});
