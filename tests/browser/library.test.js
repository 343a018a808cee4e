// phex — the library (build/pkg) in a browser page, where the core runs in a module Web Worker:
// runs, progress, cancelling, memory() and errors through the worker. Needs `make wasm` and /usr/bin/chromium.
import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from '../../scripts/serve.js';

const pkg = fileURLToPath(new URL('../../build/pkg', import.meta.url));
let server;
let browser;
let page;

before(async () => {
  assert.ok(existsSync(join(pkg, 'phex.js')), 'build/pkg is missing: run `make wasm` first');
  let url;
  ({ server, url } = await serve(pkg, 0));
  browser = await chromium.launch({ executablePath: process.env.PHEX_CHROMIUM ?? '/usr/bin/chromium', args: ['--no-sandbox'] });
  page = await browser.newPage();
  await page.goto(`${url}/phex.js`); // any page of the origin, to import the module from
});

after(async () => {
  await browser?.close();
  server?.close();
});

test('in a browser the core runs in a worker: run, cancel, memory, errors, dispose', async () => {
  const out = await page.evaluate(async () => {
    const { createPHex } = await import('/phex.js');
    const phex = await createPHex();
    const stages = new Set();
    const small = await phex.run({ surface: 'torus', faces: 300 }, { onProgress: (p) => stages.add(p.stage) });
    const memory = await phex.memory();

    // A long run, aborted once it reports progress; the next run starts a fresh worker.
    const controller = new AbortController();
    const long = phex.run({ surface: 'torus', faces: 200000 }, { signal: controller.signal, onProgress: () => controller.abort() });
    const cancelled = await long.then(() => 'resolved', (e) => e.code);
    const after = await phex.run({ surface: 'sphere', faces: 200 });
    const bad = await phex.run({ surface: 'torus', surfaceParams: { r: 3 } }).then(() => 'resolved', (e) => `${e.name} ${e.code} ${e.message}`);
    const preview = await phex.surfacePreview({ surface: 'torus' }).then(() => 'resolved', (e) => e.code);
    const capabilities = phex.capabilities();
    // The core trapping (as a file that slips through could make it) takes down the worker, not the page.
    const trapped = [];
    for (const kind of ['unreachable', 'abort', 'memory']) {
      trapped.push(await phex.debugTrap(kind).then(() => 'resolved', (e) => `${e.name} ${e.code}`));
      trapped.push((await phex.run({ surface: 'sphere', faces: 100 })).metrics.planarityMax <= 1e-9);
    }
    phex.dispose();
    const disposed = await phex.run({ surface: 'torus' }).then(() => 'resolved', (e) => e.code);
    return {
      faces: small.metrics.faceCount,
      planarity: small.metrics.planarityMax,
      typed: small.hex.positions instanceof Float64Array && small.hex.faceIndices instanceof Uint32Array,
      stages: [...stages],
      memory,
      cancelled,
      afterFaces: after.metrics.faceCount,
      bad,
      preview,
      capabilities,
      trapped,
      disposed,
    };
  });
  assert.ok(out.faces > 150 && out.planarity <= 1e-9, JSON.stringify(out));
  assert.ok(out.typed);
  assert.ok(out.stages.includes('planarize'), out.stages.join());
  assert.ok(out.memory.heapBytes >= 64 * 2 ** 20, JSON.stringify(out.memory));
  assert.equal(out.cancelled, 'cancelled');
  assert.ok(out.afterFaces > 100);
  assert.match(out.bad, /^PHexError invalid_parameter .*\br\b/);
  assert.equal(out.preview, out.capabilities.surfacePreview ? 'resolved' : 'unsupported');
  assert.deepEqual(out.trapped, Array(3).fill(['PHexError internal', true]).flat());
  assert.equal(out.disposed, 'cancelled');
});

// A run past the 2 GB the wasm heap can grow to: 'out_of_memory', and the worker holding that heap goes (a heap never
// shrinks), so the next call's core starts at its initial heap.
test('in a browser a run past the heap limit rejects with out_of_memory and the next call gets a fresh worker', async () => {
  const out = await page.evaluate(async () => {
    const { createPHex } = await import('/phex.js');
    const phex = await createPHex();
    const failed = await phex.run({ surface: 'torus', faces: 1000000, method: 'global' }).then(() => 'resolved', (e) => `${e.name} ${e.code}`);
    const memory = await phex.memory();
    const next = await phex.run({ surface: 'torus', faces: 300 });
    phex.dispose();
    return { failed, heapBytes: memory.heapBytes, planarity: next.metrics.planarityMax };
  });
  assert.equal(out.failed, 'PHexError out_of_memory');
  assert.ok(out.heapBytes < 2 ** 28, `heap ${out.heapBytes}`);
  assert.ok(out.planarity <= 1e-9);
});
