// The web client in a real browser: Debian's chromium driven by playwright-core. Starts scatterd
// on a free loopback port, loads the page, waits for a frame, drags to orbit and sees the view
// change, bakes the single pipeline's samples and watches the progress bar reach 100 %, renders
// with them, and saves a screenshot. Run by CTest: node --test client.test.mjs (SCATTERD, OUT_DIR set).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import { mkdirSync, rmSync } from 'node:fs';
import { chromium } from 'playwright-core';

function startDaemon() {
  return new Promise((resolve, reject) => {
    const cache = `${process.env.OUT_DIR || '.'}/browser-bake-cache`;
    rmSync(cache, { recursive: true, force: true });
    const proc = spawn(process.env.SCATTERD, ['serve', '--port', '0', '--cache-dir', cache],
                       { stdio: ['ignore', 'pipe', 'pipe'] });
    const timer = setTimeout(() => reject(new Error('scatterd did not start')), 20000);
    proc.stdout.on('data', (d) => {
      const m = /serving on (http:\/\/[^\s]+)/.exec(String(d));
      if (m) { clearTimeout(timer); resolve({ proc, url: m[1] }); }
    });
    proc.on('exit', (code) => reject(new Error(`scatterd exited with ${code}`)));
  });
}

test('the page streams frames, orbits on drag and bakes', { timeout: 240000 }, async () => {
  const { proc, url } = await startDaemon();
  const browser = await chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update'],
  });
  try {
    const page = await browser.newPage({ viewport: { width: 900, height: 600 } });
    await page.goto(url);
    const frames = () => page.$eval('#view', (c) => Number(c.dataset.frames || 0));
    const pixels = () => page.$eval('#view', (c) => {
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let sum = 0;
      for (let i = 0; i < d.length; i += 4) sum += d[i] * (i % 997);
      return sum;
    });
    await page.waitForFunction(() => Number(document.getElementById('view').dataset.frames || 0) >= 1,
                               null, { timeout: 60000 });
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

    // Bake the single pipeline's samples at draft quality: the bar climbs to 100 %.
    await page.selectOption('#quality', 'draft');
    const seen = [];
    await page.exposeFunction('recordProgress', (v) => seen.push(v));
    await page.evaluate(() => {
      const bar = document.getElementById('bake-progress');
      new MutationObserver(() => window.recordProgress(bar.value)).observe(bar, { attributes: true });
      setInterval(() => window.recordProgress(bar.value), 100);
    });
    await page.click('#bake');
    await page.waitForFunction(() => document.getElementById('bake-status').textContent.startsWith('done'),
                               null, { timeout: 120000 });
    assert.equal(await page.$eval('#bake-progress', (b) => b.value), 1);
    assert.ok(seen.some((v) => v > 0 && v < 1), `the bar moved through intermediate values: ${seen}`);
    // The baked pipeline now renders frames straight away.
    const m = await frames();
    await page.selectOption('#pipeline', 'single');
    await page.waitForFunction((k) => Number(document.getElementById('view').dataset.frames) > k &&
                                      /single:/.test(document.getElementById('stages').textContent), m,
                               { timeout: 60000 });
    assert.match(await page.textContent('#stages'), /single: .*splat/);
    const out = process.env.OUT_DIR || '.';
    mkdirSync(out, { recursive: true });
    await page.screenshot({ path: `${out}/browser-client.png` });
  } finally {
    await browser.close();
    proc.kill('SIGTERM');
  }
});
