// Checks scatter-load's reports for load_smoke.sh:
// node load_smoke_check.mjs TWO.json THREE.json FAILING.json
import { readFileSync } from 'node:fs';
import assert from 'node:assert/strict';

const [two, three, failing] = process.argv.slice(2).map((f) => JSON.parse(readFileSync(f, 'utf8')));
const figures = (s, what) => {
  assert.ok(s.count > 0, `${what}: no samples`);
  for (const p of ['p50', 'p95', 'p99']) assert.ok(typeof s[p] === 'number' && s[p] > 0, `${what}.${p}: ${s[p]}`);
  assert.ok(s.p50 <= s.p95 && s.p95 <= s.p99 && s.p99 <= s.max, `${what}: percentiles out of order`);
};

assert.equal(two.mode, 'live');
assert.equal(two.sessions_admitted, 2);
assert.deepEqual(two.errors, { total: 0 }, 'two sessions: no errors');
for (const s of two.per_session) {
  assert.equal(s.end, 'duration');
  assert.ok(s.frames > 0 && s.fps > 0, `session ${s.index}: ${s.frames} frames`);
  assert.ok(s.poses_sent > 50, `session ${s.index}: ${s.poses_sent} poses in 5 s at 30 Hz`);
  assert.ok(s.lights_sent > 0, `session ${s.index}: no lights sent`);
  assert.ok(s.poses_answered > 0 && s.poses_answered <= s.poses_sent);
  figures(s.pose_to_frame_ms, `session ${s.index} pose_to_frame_ms`);
}
figures(two.pose_to_frame_ms, 'pose_to_frame_ms');
assert.equal(two.frames, two.per_session[0].frames + two.per_session[1].frames);
assert.ok(two.fairness.min_fps > 0 && two.fairness.min_over_max > 0 && two.fairness.min_over_max <= 1);
assert.equal(two.rss.source, 'metrics', 'RSS from process_resident_memory_bytes');
assert.ok(two.rss.samples >= 3, `${two.rss.samples} RSS samples`);
assert.ok(two.rss.start_bytes > 1e6 && two.rss.max_bytes >= two.rss.end_bytes && two.rss.end_bytes > 1e6);

assert.equal(three.sessions_requested, 3);
assert.equal(three.sessions_admitted, 2, 'two slots, two sessions in');
assert.deepEqual(three.errors, { total: 1, refused: { 503: 1 } }, 'the third is refused, and only that');
const refused = three.per_session.filter((s) => !s.admitted);
assert.equal(refused.length, 1);
assert.equal(refused[0].end, 'refused');
assert.equal(refused[0].frames, 0);
assert.ok(three.per_session.filter((s) => s.admitted).every((s) => s.frames > 0));
const f = failing.per_session[0];
assert.equal(f.end, 'frames', 'a session whose frames all fail ends at --frames');
assert.equal(f.frames, 0);
assert.equal(f.frames_failed, 2);
assert.ok(failing.errors.total >= 2, `failed frames are errors: ${JSON.stringify(failing.errors)}`);
console.log(`two sessions: ${two.frames} frames, pose to frame p95 ${two.pose_to_frame_ms.p95} ms, ` +
            `RSS ${(two.rss.max_bytes / 1e6).toFixed(0)} MB; three: one refused (503)`);
