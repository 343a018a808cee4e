// One benchmark case in WebAssembly, in a fresh process so the heap high-water mark is this case's own.
// Usage: node --no-experimental-fetch bench/wasm-case.mjs '<params JSON>'   → one JSON line on stdout.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

// PHEX_PKG_DIR: the browser package to measure (default build/pkg).
const pkg = process.env.PHEX_PKG_DIR ?? fileURLToPath(new URL('../build/pkg', import.meta.url));
const { createPHex } = await import(pathToFileURL(join(pkg, 'phex.js')).href);

// `meshFile` names an uploaded mesh: its bytes go in as `mesh`. `repeat` (default 1) measured runs, of
// which the one with the median total is reported; `warmupFaces` (default: the case's own) sizes the
// warm-up run.
const { meshFile, repeat = 1, warmupFaces, ...params } = JSON.parse(process.argv[2]);
if (meshFile) Object.assign(params, { mesh: new Uint8Array(readFileSync(meshFile)), meshFormat: 'obj', meshName: meshFile });
const phex = await createPHex({ worker: false });
// A warm-up run first, by default of the very case measured. V8 (node, Chromium) runs new wasm code in
// its baseline compiler (Liftoff) and recompiles hot functions with its optimizing tier (TurboFan) in the
// background only after they have run for a while: a small warm-up left much of a 1k-face run in baseline
// code (3–5× slower than the same run a moment later). The figures compare steady states, as the native
// CLI's do; the warm-up's own time is reported as firstTotal (the first design of a session).
// An upload's surface is kept for the next run on it (clearUploadCache): every measured run starts without it,
// as the native CLI's fresh processes do, and one more run after them gives the time of an edit of the same
// upload (reusedTotal).
const cold = async () => meshFile && (await phex.clearUploadCache());
await cold();
const first = await phex.run(warmupFaces ? { ...params, faces: warmupFaces } : params);
const runs = [];
// Runs over 2 s scatter little: one measured run then (as run.mjs does natively).
for (let i = 0; i < (first.timings.total > 2000 ? 1 : repeat); ++i) {
  await cold();
  const started = performance.now();
  const r = await phex.run(params);
  runs.push({ r, wall: performance.now() - started });
}
runs.sort((a, b) => a.r.timings.total - b.r.timings.total);
const { r, wall } = runs[(runs.length - 1) >> 1];
const reused = meshFile ? await phex.run(params) : undefined;
const memory = await phex.memory();
console.log(JSON.stringify({
  faces: r.metrics.faceCount,
  milliseconds: { ...r.timings, wall },
  totals: runs.map((x) => x.r.timings.total),
  firstTotal: first.timings.total,
  ...(reused ? { reusedTotal: reused.timings.total, reusedTriangulate: reused.timings.triangulate, surfaceReused: reused.surfaceReused } : {}),
  iterations: r.solve.iterations,
  duality: r.duality,
  planarityMax: r.metrics.planarityMax,
  invalidFaces: r.metrics.selfIntersectingCount,
  surfaceDistanceMax: r.metrics.surfaceDistanceMax,
  peakMemoryMB: memory.heapBytes / 2 ** 20,
}));
phex.dispose();
