// phex — 200 runs in one instance leave the wasm heap flat: every run frees what it allocated.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { createPHex } from '../../build/pkg/phex.js';

const RUNS = 200;
const WARM_UP = 20;
const SLACK_BYTES = 256 * 1024; // allocator bookkeeping and fragmentation, not a leak

test(`${RUNS} runs leave the wasm heap flat`, async () => {
  const phex = await createPHex();
  // Varied work, failures included: a leak on any path shows up.
  const params = [
    { surface: 'torus', faces: 300 },
    { surface: 'sphere', faces: 200, duality: 'tangent' },
    { surface: 'hyperboloid', faces: 250 },
    { surface: 'torus', surfaceParams: { r: 2 } }, // rejected by the core (r must be less than R)
  ];
  let afterWarmUp;
  for (let i = 1; i <= RUNS; i++) {
    await phex.run(params[i % params.length]).catch((error) => assert.equal(error.code, 'invalid_parameter'));
    if (i === WARM_UP) afterWarmUp = await phex.memory();
  }
  const end = await phex.memory();
  phex.dispose();
  const measure = end.usedBytes === null ? 'heapBytes' : 'usedBytes';
  const growth = end[measure] - afterWarmUp[measure];
  console.log(`${measure}: ${afterWarmUp[measure]} after run ${WARM_UP}, ${end[measure]} after run ${RUNS} (${growth} bytes)`);
  assert.ok(growth <= SLACK_BYTES, `${measure} grew by ${growth} bytes from run ${WARM_UP} to run ${RUNS}`);
});

test('clearUploadCache gives the memory of an upload back', async () => {
  const phex = await createPHex();
  const n = 120;
  const lines = [];
  for (let j = 0; j <= n; j++) for (let i = 0; i <= n; i++) lines.push(`v ${-1 + (2 * i) / n} ${-1 + (2 * j) / n} ${0.3 * Math.sin(3 * i / n)}`);
  for (let j = 0; j < n; j++) {
    for (let i = 0; i < n; i++) {
      const a = j * (n + 1) + i + 1;
      lines.push(`f ${a} ${a + 1} ${a + n + 2}`, `f ${a} ${a + n + 2} ${a + n + 1}`);
    }
  }
  const upload = { mesh: new TextEncoder().encode(lines.join('\n')), meshFormat: 'obj', faces: 200 };
  await phex.run({ surface: 'torus', faces: 200 });
  const before = await phex.memory();
  if (before.usedBytes === null) return phex.dispose(); // this build cannot tell
  await phex.run(upload);
  const kept = await phex.memory();
  await phex.clearUploadCache();
  const after = await phex.memory();
  phex.dispose();
  console.log(`used bytes: ${before.usedBytes} before the upload, ${kept.usedBytes} with it kept, ${after.usedBytes} after clearUploadCache`);
  assert.ok(kept.usedBytes > before.usedBytes + 2 ** 20, 'the upload\'s surface is kept');
  assert.ok(after.usedBytes <= before.usedBytes + SLACK_BYTES, 'and let go');
});

// A run past what the WebAssembly heap can grow to (2 GB) rejects with 'out_of_memory', naming the remedy, and is no
// bug: the heap, grown to its limit, never shrinks, so the next call runs on a fresh core with its memory back.
test("a run past the heap's limit rejects with out_of_memory; the next call runs on a fresh core", async () => {
  const phex = await createPHex();
  // The global method's field mesh for a million faces on the torus (5M vertices) runs out in a few seconds.
  await assert.rejects(phex.run({ surface: 'torus', faces: 1000000, method: 'global' }), (error) => {
    assert.equal(error.code, 'out_of_memory');
    assert.match(error.message, /out of memory.*fewer faces/);
    return true;
  });
  const fresh = await phex.memory();
  const r = await phex.run({ surface: 'torus', faces: 300 });
  phex.dispose();
  console.log(`heap after the failed run: ${fresh.heapBytes} bytes`);
  assert.ok(fresh.heapBytes < 2 ** 28, `the heap is back to a fresh core's (${fresh.heapBytes} bytes)`);
  assert.ok(r.metrics.faceCount > 200);
});
