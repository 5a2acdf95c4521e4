// The web client in a real browser: Debian's chromium driven by playwright-core. Starts scatterd
// on a free loopback port and loads the page: its menus are the server's registry; its first
// frame is translucent (green from the jade medium, where the surface render of the same view is
// grey); dragging keeps the canvas's size; a pipeline change keeps the view; light controls edit
// the scene's lights and the light's marker follows shift-drag; a material change re-renders and
// a bad one shows its error; the frame saves as PNG; an uploaded mesh and density grid are shown;
// a bake shows its progress and a cancel button; the page works with --token. A still view of the
// sphere shows its estimated error falling. Touch, drag and drop and the busy line:
// touch.test.mjs. Screenshots go to OUT_DIR. Run by CTest: node --test client.test.mjs.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { checksum, colourOf, frameAfter, frames, launch, recordSocket, startDaemon } from './page_helpers.mjs';

test('first sight: a translucent jade bunny, steered without losing the view', { timeout: 280000 }, async () => {
  const { proc, url } = await startDaemon(['--refine-max-passes', '0']);
  const browser = await launch();
  const out = process.env.OUT_DIR || '.';
  mkdirSync(out, { recursive: true });
  try {
    const registry = (await (await fetch(new URL('/api/pipelines', url))).json()).pipelines;
    const info = (name) => registry.find((p) => p.name === name);
    const page = await browser.newPage({ viewport: { width: 1000, height: 800 } });
    const sock = recordSocket(page);
    await page.goto(url);
    await frameAfter(page, 0);
    await page.screenshot({ path: `${out}/browser-first-sight.png` });

    // The menus are the registry's, in its order; the first screen is jade by thickness.
    const options = (id) => page.$$eval(`#${id} option`, (os) => os.map((o) => o.value));
    assert.deepEqual(await options('pipeline'), registry.map((p) => p.name));
    assert.equal(await page.inputValue('#pipeline'), 'thickness');
    assert.equal(await page.inputValue('#scene'), 'jade');
    assert.deepEqual(await options('quality'), info('thickness').qualities.map((q) => q.name));
    assert.deepEqual(await options('terms'), info('thickness').terms);
    assert.ok((await options('scene')).includes('cube-torus'), 'the scene menu lists the server\'s scenes');
    const first = sock.sent.find((m) => m.type === 'hello');
    assert.equal(first.scene_name, 'jade');
    assert.equal(first.keep_view, false);
    assert.ok(first.request >= 1);
    // The plan is shown: stages run (and skipped) with their reasons.
    assert.match(await page.textContent('#plan'), /ran shadow_maps: /);

    // Translucent: the jade medium's light comes out green (its scattering albedo is highest in
    // green), while the surface render of the same view is the grey Blinn-Phong material.
    const jade = await colourOf(page);
    assert.ok(jade.n > 1000, `the bunny covers the view: ${jade.n} pixels`);
    assert.ok(jade.mean[1] > 1.15 * jade.mean[0], `green outweighs red in the translucent frame: ${jade.mean}`);
    // Still, the multiple-scattering term (psf's, at half size) is added: the hello asked for it,
    // and the frame that has it is brighter, and still green.
    assert.equal(first.composite && first.composite.pipeline, 'psf');
    await page.waitForFunction(() => document.getElementById('view').dataset.stage === 'multiple', null, { timeout: 90000 });
    const glow = await colourOf(page);
    const sum = (c) => c.mean.reduce((a, b) => a + b, 0) * c.n;
    assert.ok(sum(glow) > 1.1 * sum(jade), `the multiple term adds light: ${jade.mean} x ${jade.n} -> ${glow.mean} x ${glow.n}`);
    assert.ok(glow.mean[1] > 1.15 * glow.mean[0], `green still outweighs red: ${glow.mean}`);
    assert.match(await page.textContent('#refine'), /multiple from psf/);
    await page.screenshot({ path: `${out}/browser-first-sight-multiple.png` });

    // Orbit: reduced frames come while dragging, drawn at the canvas's size on the page.
    const box = await page.locator('#view').boundingBox();
    const n = await frames(page);
    await page.mouse.move(box.x + 250, box.y + 250);
    await page.mouse.down();
    let sawReduced = false;
    for (let i = 0; i < 12; ++i) {
      await page.mouse.move(box.x + 250 + 8 * i, box.y + 250 + i);
      await page.waitForTimeout(60);
      sawReduced ||= /moving/.test(await page.textContent('#size'));
      const b = await page.locator('#view').boundingBox();
      assert.deepEqual([b.width, b.height], [box.width, box.height], 'the canvas keeps its size while dragging');
    }
    await page.waitForFunction(() => /moving/.test(document.getElementById('size').textContent) ||
                                     Number(document.getElementById('view').dataset.revision) > 0, null, { timeout: 30000 });
    await page.mouse.up();
    await frameAfter(page, n);
    await page.waitForTimeout(2500);  // the still frame after the drag
    // The overlay gives a rate while frames come and says "still" after, never "0.0 fps".
    assert.match(await page.textContent('#fps'), /^(still|\d+\.\d fps)$/);
    assert.notEqual(await page.textContent('#fps'), '0.0 fps');
    const cameraSent = sock.sent.filter((m) => m.type === 'camera').at(-1);
    assert.ok(cameraSent, 'the drag sent camera poses');

    // Another pipeline keeps the view: the hello says keep_view, the server's scene message
    // carries the camera the page sent, and the surface frame is grey where jade was green.
    let k = sock.received.length;
    const h = sock.sent.length;
    await page.selectOption('#pipeline', 'surface');
    const scene = await sock.next(sock.received, k, (m) => m.type === 'scene');
    assert.equal(scene.kept_view, true);
    assert.equal((await sock.next(sock.sent, h, (m) => m.type === 'hello')).keep_view, true);
    scene.camera.position.forEach((v, i) => assert.ok(Math.abs(v - cameraSent.position[i]) < 1e-6,
                                                      `the camera stays: ${scene.camera.position} vs ${cameraSent.position}`));
    await page.waitForFunction(() => document.getElementById('view').dataset.pipeline === 'surface', null, { timeout: 60000 });
    const grey = await colourOf(page);
    assert.ok(Math.abs(grey.mean[1] - grey.mean[0]) < 0.1 * grey.mean[0], `the surface render is grey: ${grey.mean}`);
    await page.screenshot({ path: `${out}/browser-surface.png` });

    // Light controls edit the scene's lights: cube-torus keeps its two, the first one changed.
    k = sock.received.length;
    await page.selectOption('#scene', 'cube-torus');
    const cube = await sock.next(sock.received, k, (m) => m.type === 'scene' && m.lights.length === 2);
    await page.waitForTimeout(500);
    const l = sock.sent.length;
    await page.fill('#light-intensity', '80');
    await page.dispatchEvent('#light-intensity', 'change');
    const lights = (await sock.next(sock.sent, l, (m) => m.type === 'lights')).lights;
    assert.equal(lights.length, 2);
    assert.equal(lights[0].intensity, 80);
    assert.deepEqual(lights[1], cube.lights[1]);
    // Shift-drag moves the light in the screen's plane; its marker moves with it.
    const mx = await page.$eval('#marker', (m) => Number(m.dataset.x));
    await page.keyboard.down('Shift');
    await page.mouse.move(box.x + 200, box.y + 200);
    await page.mouse.down();
    await page.mouse.move(box.x + 260, box.y + 200, { steps: 5 });
    await page.mouse.up();
    await page.keyboard.up('Shift');
    const mx2 = await page.$eval('#marker', (m) => Number(m.dataset.x));
    assert.ok(mx2 > mx + 10, `the light's marker moved right with the drag: ${mx} -> ${mx2}`);

    // Keyboard orbit: the arrow keys send camera poses.
    const c = sock.sent.length;
    await page.focus('#view');
    await page.keyboard.press('ArrowLeft');
    await sock.next(sock.sent, c, (m) => m.type === 'camera');

    // A material change re-renders: a new hello with the medium, and a different image.
    await page.selectOption('#scene', 'jade');
    await page.selectOption('#pipeline', 'thickness');
    await page.waitForFunction(() => document.getElementById('view').dataset.pipeline === 'thickness', null, { timeout: 60000 });
    await page.waitForTimeout(2500);
    const before = await checksum(page), m0 = await frames(page), hm = sock.sent.length;
    await page.fill('#m-scatter', '8');
    await page.fill('#m-absorb-color', '#2040ff');
    await page.click('#m-apply');
    const mh = await sock.next(sock.sent, hm, (m) => m.type === 'hello');
    assert.equal(mh.scene_name, 'jade');
    assert.equal(Math.max(...mh.medium.sigma_s).toFixed(3), '8.000');
    await page.waitForFunction((r) => document.getElementById('view').dataset.request === String(r), mh.request, { timeout: 60000 });
    await frameAfter(page, m0);
    assert.notEqual(await checksum(page), before, 'the new material re-rendered the view');
    await page.screenshot({ path: `${out}/browser-material.png` });

    // A bad material value: the server's error shows in the page, naming the field, until the
    // next frame.
    await page.fill('#m-g', '5');
    await page.click('#m-apply');
    await page.waitForSelector('#error', { state: 'visible', timeout: 30000 });
    assert.match(await page.textContent('#error'), /medium\.g/);
    await page.screenshot({ path: `${out}/browser-material-error.png` });
    await page.fill('#m-g', '0.3');
    await page.click('#m-apply');
    await page.waitForSelector('#error', { state: 'hidden', timeout: 60000 });

    // Save the frame as PNG: a download whose bytes are a PNG.
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#save-png')]);
    const saved = `${out}/browser-saved.png`;
    await download.saveAs(saved);
    assert.deepEqual([...readFileSync(saved).subarray(0, 4)], [0x89, 0x50, 0x4e, 0x47]);
    // Save the linear frame as EXR: the session's snapshot, downloaded (OpenEXR's magic number).
    const [exr] = await Promise.all([page.waitForEvent('download', { timeout: 60000 }), page.click('#save-exr')]);
    const savedExr = `${out}/browser-saved.exr`;
    await exr.saveAs(savedExr);
    assert.deepEqual([...readFileSync(savedExr).subarray(0, 4)], [0x76, 0x2f, 0x31, 0x01]);

    // Upload a mesh (a closed cube): it is shown in the current medium.
    const obj = `${out}/browser-cube.obj`;
    writeFileSync(obj, ['v -0.6 -0.6 -0.6', 'v 0.6 -0.6 -0.6', 'v 0.6 0.6 -0.6', 'v -0.6 0.6 -0.6',
                        'v -0.6 -0.6 0.6', 'v 0.6 -0.6 0.6', 'v 0.6 0.6 0.6', 'v -0.6 0.6 0.6',
                        'f 1 3 2', 'f 1 4 3', 'f 5 6 7', 'f 5 7 8', 'f 1 2 6', 'f 1 6 5',
                        'f 2 3 7', 'f 2 7 6', 'f 3 4 8', 'f 3 8 7', 'f 4 1 5', 'f 4 5 8'].join('\n') + '\n');
    const u = await frames(page), hu = sock.sent.length;
    await page.setInputFiles('#upload', obj);
    const uh = await sock.next(sock.sent, hu, (m) => m.type === 'hello');
    assert.ok(uh.scene && uh.scene.mesh.asset, `the hello shows the upload: ${JSON.stringify(uh.scene && uh.scene.mesh)}`);
    // Framed whole: the fitted box's bounding sphere (radius sqrt 3) within the field of view.
    const cam = uh.scene.camera;
    const dist = Math.hypot(...cam.position.map((v, i) => v - cam.target[i]));
    assert.ok(dist * Math.sin(((cam.fov_deg || 40) * Math.PI) / 360) >= Math.sqrt(3),
              `the uploaded mesh is framed whole: ${JSON.stringify(cam)}`);
    await page.waitForFunction((r) => document.getElementById('view').dataset.request === String(r), uh.request, { timeout: 60000 });
    assert.ok(await frames(page) > u);
    await page.screenshot({ path: `${out}/browser-upload.png` });

    // Upload a density grid (8^3 float32, denser towards +x) for the uploaded cube: the hello
    // carries it as the medium's density and the view re-renders. A file of the wrong size is
    // refused in the page, by name, before anything is sent.
    const grid = `${out}/browser-grid.raw`;
    const values = new Float32Array(512);
    for (let i = 0; i < 512; ++i) values[i] = 0.1 + 0.3 * (i % 8);
    writeFileSync(grid, Buffer.from(values.buffer));
    writeFileSync(`${out}/browser-grid-short.raw`, Buffer.from(values.buffer, 0, 100));
    // (psf, at draft: thickness takes only homogeneous media.)
    await page.selectOption('#pipeline', 'psf');
    // The single term was thickness's only one, not the user's choice: psf shows its default.
    assert.equal(await page.inputValue('#terms'), info('psf').default_terms);
    await page.selectOption('#quality', 'draft');
    await page.waitForFunction(() => document.getElementById('view').dataset.pipeline === 'psf', null, { timeout: 90000 });
    await page.waitForTimeout(2500);
    await page.fill('#grid-dims', '8,8,8');
    await page.setInputFiles('#upload-grid', `${out}/browser-grid-short.raw`);
    await page.waitForSelector('#error', { state: 'visible', timeout: 10000 });
    assert.match(await page.textContent('#error'), /browser-grid-short\.raw: 100 bytes, but 8 x 8 x 8 float32 values are 2048/);
    const ungridded = await checksum(page), g0 = await frames(page), hg = sock.sent.length;
    await page.setInputFiles('#upload-grid', grid);
    const gh = await sock.next(sock.sent, hg, (m) => m.type === 'hello');
    const density = gh.scene && gh.scene.medium && gh.scene.medium.density;
    assert.ok(density && density.type === 'grid' && density.asset, `the hello carries the grid: ${JSON.stringify(density)}`);
    assert.equal(gh.keep_view, true);
    await page.waitForFunction((r) => document.getElementById('view').dataset.request === String(r), gh.request, { timeout: 60000 });
    await frameAfter(page, g0);
    assert.notEqual(await checksum(page), ungridded, 'the grid changes the image');
    await page.screenshot({ path: `${out}/browser-grid.png` });

    // Bake the single pipeline's samples at draft quality on the bunny: the bar climbs to 100 %,
    // with a cancel button while it runs.
    await page.selectOption('#scene', 'bunny');
    await page.selectOption('#quality', 'draft');
    await page.selectOption('#pipeline', 'single');
    assert.equal(await page.isVisible('#bake'), true);
    const seen = [];
    await page.exposeFunction('recordProgress', (v, cancel) => seen.push([v, cancel]));
    await page.evaluate(() => setInterval(() => window.recordProgress(
      document.getElementById('bake-progress').value, !document.getElementById('bake-cancel').hidden), 100));
    await page.click('#bake');
    await page.waitForFunction(() => document.getElementById('bake-status').textContent.startsWith('done'),
                               null, { timeout: 150000 });
    assert.equal(await page.$eval('#bake-progress', (b) => b.value), 1);
    assert.ok(seen.some(([v, cancel]) => v > 0 && v < 1 && cancel), `the bar moved, with a cancel button: ${JSON.stringify(seen.slice(0, 20))}`);
    await page.waitForFunction(() => /single:/.test(document.getElementById('stages').textContent), null, { timeout: 90000 });
    await page.screenshot({ path: `${out}/browser-client.png` });
    await page.close();

    // While /api/pipelines fails the page says so, and fills its menus once it answers.
    const failing = await browser.newPage({ viewport: { width: 900, height: 600 } });
    await failing.route('**/api/pipelines', (r) => r.fulfill(
      { status: 503, contentType: 'application/json', body: JSON.stringify({ error: 'the server is stopping' }) }));
    await failing.goto(url);
    await failing.waitForSelector('#error', { state: 'visible', timeout: 10000 });
    assert.match(await failing.textContent('#error'), /GET \/api\/pipelines.*the server is stopping/);
    await failing.screenshot({ path: `${out}/browser-client-error.png` });
    await failing.unroute('**/api/pipelines');
    await failing.waitForSelector('#error', { state: 'hidden', timeout: 10000 });
    assert.equal(await failing.inputValue('#pipeline'), 'thickness');
    await failing.close();
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});

// With --token, /?token=T (any characters, percent-encoded) loads the page, its assets and its
// frames (the token then travels in a cookie); a wrong token reads as a page, not JSON.
test('the page works with --token', { timeout: 120000 }, async () => {
  const token = 'a+b/c=d&e f';
  const { proc, url } = await startDaemon(['--token', token, '--refine-max-passes', '0']);
  const browser = await launch();
  try {
    const page = await browser.newPage();
    await page.goto(new URL('/?token=' + encodeURIComponent(token), url).href);
    await frameAfter(page, 0);
    assert.equal(await page.$eval('aside', (a) => getComputedStyle(a).display), 'flex', 'style.css loaded');
    const wrong = await browser.newPage();
    const r = await wrong.goto(new URL('/?token=nope', url).href);
    assert.equal(r.status(), 401);
    assert.match(await wrong.textContent('h1'), /needs a token/);
    assert.equal((await fetch(new URL('/api/health', url))).status, 401, 'the API still needs it');
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});

// Still, the view is refined: thickness's full frame (no estimate), the composite with psf's
// multiple term (its calibrated error), thickness's high quality (none: the composite's stays the
// mark), then the reference's passes, whose estimated error the overlay shows, falling, until it
// is under the floor (1 %) or the passes end.
test('a still view shows its estimated error converging', { timeout: 180000 }, async () => {
  const { proc, url } = await startDaemon(['--refine-pass-s', '0.5', '--refine-max-passes', '40']);
  const browser = await launch();
  try {
    const page = await browser.newPage({ viewport: { width: 900, height: 600 } });
    await page.goto(url);
    await page.waitForFunction(() => Number(document.getElementById('view').dataset.frames || 0) >= 1,
                               null, { timeout: 60000 });
    await page.selectOption('#scene', 'sphere');
    await page.selectOption('#pipeline', 'thickness');
    await page.waitForTimeout(1000);  // the sphere's scene message: the zoom's bounds
    // Zoomed out (the orbit's radius 3.6 x e^1.2 = 12): the sphere covers a tenth of the pixels
    // it did, and the reference's passes converge that much sooner.
    const box = await page.locator('#view').boundingBox();
    await page.mouse.move(box.x + 250, box.y + 250);
    await page.mouse.wheel(0, 1200);
    // The overlay's line, as the user reads it, each time it changes.
    const seen = [];
    await page.exposeFunction('recordRefine', (text) => seen.push(text));
    const next = [];  // the line under it: passes not shown yet
    await page.exposeFunction('recordNext', (text) => next.push(text));
    await page.evaluate(() => {
      const watch = (id, record) => {
        const line = document.getElementById(id);
        new MutationObserver(() => record(line.textContent))
          .observe(line, { childList: true, characterData: true, subtree: true });
      };
      watch('refine', window.recordRefine);
      watch('refine-next', window.recordNext);
    });
    const percent = (t) => { const m = /error ≈ ([\d.]+) %/.exec(t); return m ? Number(m[1]) : null; };
    const errors = () => seen.map(percent).filter((e) => e !== null);
    const start = Date.now();
    while (Date.now() - start < 150000) {
      const last = seen.at(-1) || '';
      if (errors().length >= 3 || /converged|refined/.test(last)) break;
      await new Promise((ok) => setTimeout(ok, 100));
    }
    const e = errors();
    console.log(`refinement in the page after ${((Date.now() - start) / 1000).toFixed(1)} s: ${JSON.stringify(seen)}; ` +
                `${next.length} passes not shown, the first ${JSON.stringify(next.slice(0, 2))}`);
    assert.ok(e.length >= 2, `the page showed an error estimate that changed: ${JSON.stringify(seen)}`);
    for (let i = 1; i < e.length; ++i) assert.ok(e[i] < e[i - 1], `each shown error is lower: ${e}`);
    assert.ok(seen.some((t) => /error ≈ [\d.]+ % · (converging \(reference pass \d+, \d+ spp\)|converged)/.test(t)),
              `it says it is converging, with the pass and samples: ${JSON.stringify(seen)}`);
    // Before the first pass was shown, the passes that were not said how far they got.
    assert.ok(next.some((t) => /^next: reference pass \d+, \d+ spp ≈ [\d.]+ %$/.test(t)),
              `the passes not shown yet: ${JSON.stringify(next.slice(0, 5))}`);
    const out = process.env.OUT_DIR || '.';
    mkdirSync(out, { recursive: true });
    await page.screenshot({ path: `${out}/browser-client-refine.png` });
    // Moving starts over: the reduced and thickness frames carry no estimate, and the line says so.
    await page.mouse.move(box.x + 250, box.y + 250);
    await page.mouse.down();
    await page.mouse.move(box.x + 300, box.y + 250, { steps: 4 });
    await page.mouse.up();
    await page.waitForFunction(() => Number(document.getElementById('view').dataset.revision) > 0 &&
                                     !/error/.test(document.getElementById('refine').textContent),
                               null, { timeout: 60000 });
    await page.close();
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});
