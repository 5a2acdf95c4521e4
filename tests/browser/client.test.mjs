// The web client in a real browser: Debian's chromium driven by playwright-core. Starts scatterd
// on a free loopback port, loads the page, checks that its menus are the server's registry
// (GET /api/pipelines), waits for a frame, drags to orbit and sees the view change, bakes the
// single pipeline's samples and watches the progress bar reach 100 %, renders with them, checks
// the terms menu of a pipeline with several terms and what the hello sends, saves a screenshot,
// and shows the page's error while /api/pipelines fails; a still view of the sphere by thickness
// shows its estimated error falling as the server refines it. Run by CTest: node --test
// client.test.mjs (SCATTERD, OUT_DIR set).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { mkdirSync, rmSync } from 'node:fs';
import { chromium } from 'playwright-core';

function startDaemon(args = []) {
  return new Promise((resolve, reject) => {
    const cache = `${process.env.OUT_DIR || '.'}/browser-bake-cache`;
    rmSync(cache, { recursive: true, force: true });
    const proc = spawn(process.env.SCATTERD, ['serve', '--port', '0', '--cache-dir', cache, ...args],
                       { stdio: ['ignore', 'pipe', 'pipe'] });
    const timer = setTimeout(() => reject(new Error('scatterd did not start')), 20000);
    proc.stdout.on('data', (d) => {
      const m = /serving on (http:\/\/[^\s]+)/.exec(String(d));
      if (m) { clearTimeout(timer); resolve({ proc, url: m[1] }); }
    });
    proc.on('exit', (code) => reject(new Error(`scatterd exited with ${code}`)));
  });
}

const launch = () => chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update'],
});

test('the page streams frames, orbits on drag and bakes', { timeout: 240000 }, async () => {
  // Without reference passes: a still view's passes would share the 2 cores with the bake timed
  // here (refinement has its own test below).
  const { proc, url } = await startDaemon(['--refine-max-passes', '0']);
  const browser = await launch();
  try {
    const registry = (await (await fetch(new URL('/api/pipelines', url))).json()).pipelines;
    const info = (name) => registry.find((p) => p.name === name);
    const page = await browser.newPage({ viewport: { width: 900, height: 600 } });
    const hellos = [];  // the hello messages the page sends, in order
    page.on('websocket', (ws) => ws.on('framesent', ({ payload }) => {
      try { const m = JSON.parse(payload); if (m.type === 'hello') hellos.push(m); } catch { /* binary */ }
    }));
    // The newest hello once there are more than k (the page sends it on the event it handles).
    const helloAfter = async (k) => {
      for (let t = 0; hellos.length <= k; t += 20) {
        if (t > 10000) throw new Error(`no hello after the ${k}th`);
        await new Promise((ok) => setTimeout(ok, 20));
      }
      return hellos.at(-1);
    };
    await page.goto(url);
    const options = (id) => page.$$eval(`#${id} option`, (os) => os.map((o) => ({ value: o.value, title: o.title })));
    const frames = () => page.$eval('#view', (c) => Number(c.dataset.frames || 0));
    const pixels = () => page.$eval('#view', (c) => {
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let sum = 0;
      for (let i = 0; i < d.length; i += 4) sum += d[i] * (i % 997);
      return sum;
    });
    await page.waitForFunction(() => Number(document.getElementById('view').dataset.frames || 0) >= 1,
                               null, { timeout: 60000 });

    // The menus are the registry's: every pipeline, in its order, with its summary; surface first
    // selected, with its qualities and terms; it does not bake, so there is no bake button.
    assert.deepEqual(await options('pipeline'), registry.map((p) => ({ value: p.name, title: p.summary })));
    assert.equal(await page.inputValue('#pipeline'), 'surface');
    assert.deepEqual((await options('quality')).map((o) => o.value), info('surface').qualities.map((q) => q.name));
    assert.deepEqual((await options('terms')).map((o) => o.value), info('surface').terms);
    assert.equal(info('surface').bakes, false);
    assert.equal(await page.isVisible('#bake'), false, 'no bake button for a pipeline that does not bake');
    assert.equal(await page.isDisabled('#bake'), true);
    assert.deepEqual(await helloAfter(0), { type: 'hello', scene_name: 'bunny', pipeline: 'surface', format: 'jpg',
                                  terms: info('surface').default_terms, settings: {} });

    const before = await pixels();
    assert.ok(before > 0, 'the first frame shows something');
    const n = await frames();
    const box = await page.locator('#view').boundingBox();
    await page.mouse.move(box.x + 250, box.y + 250);
    await page.mouse.down();
    await page.mouse.move(box.x + 330, box.y + 260, { steps: 8 });
    await page.mouse.up();
    await page.waitForFunction((k) => {
      const c = document.getElementById('view');
      return Number(c.dataset.frames) > k && Number(c.dataset.revision) > 0;
    }, n, { timeout: 60000 });
    // Frames keep coming until the newest pose is shown; give the last one a moment.
    await page.waitForTimeout(1500);
    const after = await pixels();
    assert.notEqual(after, before, 'the view changed after the drag');
    assert.match(await page.textContent('#stages'), /surface: .*raster/);

    // Draft quality on a pipeline that has it is kept when switching to single (so the view's
    // own render bakes draft samples, not the default's many), whose settings the hello sends.
    const draft = (name) => info(name).qualities.find((q) => q.name === 'draft').settings;
    await page.selectOption('#pipeline', 'thickness');
    let k = hellos.length;
    await page.selectOption('#quality', 'draft');
    assert.deepEqual((await helloAfter(k)).settings, draft('thickness'));
    assert.equal(info('single').bakes, true);
    k = hellos.length;
    await page.selectOption('#pipeline', 'single');
    assert.equal(await page.inputValue('#quality'), 'draft');
    assert.deepEqual(await helloAfter(k), { type: 'hello', scene_name: 'bunny', pipeline: 'single', format: 'jpg',
                                      terms: info('single').default_terms, settings: draft('single') });

    // Bake the single pipeline's samples at draft quality: the bar climbs to 100 %.
    assert.equal(await page.isVisible('#bake'), true);
    const seen = [];
    await page.exposeFunction('recordProgress', (v) => seen.push(v));
    await page.evaluate(() => {
      const bar = document.getElementById('bake-progress');
      new MutationObserver(() => window.recordProgress(bar.value)).observe(bar, { attributes: true });
      setInterval(() => window.recordProgress(bar.value), 100);
    });
    const sent = hellos.length, m = await frames();
    await page.click('#bake');
    await page.waitForFunction(() => document.getElementById('bake-status').textContent.startsWith('done'),
                               null, { timeout: 120000 });
    assert.equal(await page.$eval('#bake-progress', (b) => b.value), 1);
    assert.ok(seen.some((v) => v > 0 && v < 1), `the bar moved through intermediate values: ${seen}`);
    // The bake re-sent the hello (the same: the view picks the product up); single renders frames.
    assert.deepEqual(await helloAfter(sent), hellos[sent - 1]);
    await page.waitForFunction((k) => Number(document.getElementById('view').dataset.frames) > k &&
                                      /single:/.test(document.getElementById('stages').textContent), m,
                               { timeout: 60000 });
    assert.match(await page.textContent('#stages'), /single: .*splat/);
    const out = process.env.OUT_DIR || '.';
    mkdirSync(out, { recursive: true });
    await page.screenshot({ path: `${out}/browser-client.png` });

    // A pipeline with several terms: its terms fill the menu, its default selected and sent; a
    // choice from the menu is sent too. It does not bake: the bake button goes.
    const several = registry.find((p) => p.terms.length > 1 && !p.bakes);
    k = hellos.length;
    await page.selectOption('#pipeline', several.name);
    assert.deepEqual((await options('terms')).map((o) => o.value), several.terms);
    assert.equal(await page.inputValue('#terms'), several.default_terms);
    const h = await helloAfter(k);
    assert.equal(h.pipeline, several.name);
    assert.equal(h.terms, several.default_terms);
    const other = several.terms.find((t) => t !== several.default_terms);
    k = hellos.length;
    await page.selectOption('#terms', other);
    assert.equal((await helloAfter(k)).terms, other);
    assert.equal(await page.isVisible('#bake'), false);
    assert.equal(await page.isDisabled('#bake'), true);
    await page.screenshot({ path: `${out}/browser-client-terms.png` });
    await page.close();  // its session's render stops

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
    assert.equal(await failing.inputValue('#pipeline'), 'surface');
    await failing.close();
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});

// Still, the view is refined: thickness's frames (no estimate), then the reference's passes, whose
// estimated error the overlay shows, falling, until it is under the floor (1 %) or the passes end.
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
