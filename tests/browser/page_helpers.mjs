// Shared by the browser tests (client.test.mjs, touch.test.mjs): scatterd on a free loopback
// port, Debian's chromium, and what the tests read off the page and its WebSocket.
import { spawn } from 'node:child_process';
import { rmSync } from 'node:fs';
import { chromium } from 'playwright-core';

// `tag` names the bake cache it starts empty (one per test file: the files run side by side).
export function startDaemon(args = [], tag = 'client') {
  return new Promise((resolve, reject) => {
    const cache = `${process.env.OUT_DIR || '.'}/browser-bake-cache-${tag}`;
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

export const launch = () => chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update'],
});

// Mean R, G, B over the pixels the object covers (any channel above 8), and their count.
export const colourOf = (page) => page.$eval('#view', (c) => {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  const sum = [0, 0, 0];
  let n = 0;
  for (let i = 0; i < d.length; i += 4) {
    if (Math.max(d[i], d[i + 1], d[i + 2]) <= 8) continue;
    sum[0] += d[i]; sum[1] += d[i + 1]; sum[2] += d[i + 2]; n += 1;
  }
  return { mean: sum.map((s) => s / Math.max(1, n)), n };
});
export const checksum = (page) => page.$eval('#view', (c) => {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let sum = 0;
  for (let i = 0; i < d.length; i += 4) sum += d[i] * (i % 997) + d[i + 1];
  return sum;
});
// Waits for a frame drawn after `k` frames that answers the page's newest hello.
export const frameAfter = (page, k, timeout = 90000) => page.waitForFunction((k) => {
  const c = document.getElementById('view');
  return Number(c.dataset.frames || 0) > k;
}, k, { timeout });
export const frames = (page) => page.$eval('#view', (c) => Number(c.dataset.frames || 0));

// Records what the page sends and receives over its WebSocket (JSON messages only).
export function recordSocket(page) {
  const sent = [], received = [];
  page.on('websocket', (ws) => {
    ws.on('framesent', ({ payload }) => { try { sent.push(JSON.parse(payload)); } catch { /* binary */ } });
    ws.on('framereceived', ({ payload }) => { try { received.push(JSON.parse(payload)); } catch { /* binary */ } });
  });
  const next = async (list, k, pred) => {
    for (let t = 0; ; t += 20) {
      const m = list.slice(k).find(pred);
      if (m) return m;
      if (t > 60000) throw new Error(`no such message after ${k}: ${JSON.stringify(list.slice(k).slice(-5))}`);
      await new Promise((ok) => setTimeout(ok, 20));
    }
  };
  return { sent, received, next };
}
