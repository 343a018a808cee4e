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
