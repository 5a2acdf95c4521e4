// Markdown tables from scatter-load reports: node bench/load-table.mjs REPORT.json ...
// Live runs: one row each (median per-session fps, fairness, pose-to-frame percentiles, ...);
// REST runs: one row per route.
import { readFileSync } from 'node:fs';
import { basename } from 'node:path';

const reports = process.argv.slice(2).map((f) => ({ file: basename(f), r: JSON.parse(readFileSync(f, 'utf8')) }));
const median = (a) => { const s = [...a].sort((x, y) => x - y); return s.length ? s[Math.floor((s.length - 1) / 2)] : null; };
const mb = (b) => (b == null ? '-' : (b / 1048576).toFixed(0));
const pct = (s) => (s && s.count ? `${s.p50} / ${s.p95} / ${s.p99}` : '-');
const errors = (e) => Object.entries(e).filter(([k]) => k !== 'total')
  .map(([k, v]) => `${k} ${Object.entries(v).map(([d, n]) => `${d}: ${n}`).join(', ')}`).join('; ') || 'none';

const live = reports.filter(({ r }) => r.mode === 'live');
if (live.length) {
  console.log('| run | sessions in / asked | fps per session (median; min-max) | fps total | pose to frame p50 / p95 / p99 (ms) | render p50 / p95 (ms) | header to image p50 (ms) | poses sent / coalesced | errors | RSS MB start / max / end |');
  console.log('| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |');
  for (const { file, r } of live) {
    const fps = r.per_session.filter((s) => s.admitted).map((s) => s.fps);
    console.log(`| ${file.replace('.json', '')} (${r.scene}/${r.pipeline}, ${r.duration_s} s) | ${r.sessions_admitted} / ${r.sessions_requested} | ` +
      `${median(fps)}; ${r.fairness.min_fps}-${r.fairness.max_fps} (min/max ${r.fairness.min_over_max}) | ${r.fps_total} | ` +
      `${pct(r.pose_to_frame_ms)} | ${r.render_ms.count ? `${r.render_ms.p50} / ${r.render_ms.p95}` : '-'} | ` +
      `${r.header_to_image_ms.count ? r.header_to_image_ms.p50 : '-'} | ${r.poses_sent} / ${r.poses_coalesced} | ${errors(r.errors)} | ` +
      `${mb(r.rss.start_bytes)} / ${mb(r.rss.max_bytes)} / ${mb(r.rss.end_bytes)} |`);
  }
}
const rest = reports.filter(({ r }) => r.mode === 'rest');
if (rest.length) {
  console.log('\n| run | route | requests (status: n) | latency p50 / p95 / p99 (ms) | errors |');
  console.log('| --- | --- | --- | --- | --- |');
  for (const { file, r } of rest)
    for (const [route, x] of Object.entries(r.routes))
      console.log(`| ${file.replace('.json', '')} (${r.clients} clients, ${r.duration_s} s) | ${route} | ` +
        `${Object.entries(x.status).map(([s, n]) => `${s}: ${n}`).join(', ')} | ${pct(x.ms)} | ${errors(r.errors)} |`);
}
