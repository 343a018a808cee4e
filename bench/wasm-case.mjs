// One benchmark case in WebAssembly, in a fresh process so the heap high-water mark is this case's own.
// Usage: node --no-experimental-fetch bench/wasm-case.mjs '<params JSON>'   → one JSON line on stdout.
import { readFileSync } from 'node:fs';
import { createPHex } from '../build/pkg/phex.js';

// `meshFile` names an uploaded mesh: its bytes go in as `mesh`.
const { meshFile, ...params } = JSON.parse(process.argv[2]);
if (meshFile) Object.assign(params, { mesh: new Uint8Array(readFileSync(meshFile)), meshFormat: 'obj', meshName: meshFile });
const phex = await createPHex({ worker: false });
// A small run first, so the engine has compiled the hot code with its optimizing tier as it would have
// after the first design in a session; the figures then compare steady states.
await phex.run({ ...params, faces: 200 });
const started = performance.now();
const r = await phex.run(params);
const wall = performance.now() - started;
const memory = await phex.memory();
console.log(JSON.stringify({
  faces: r.metrics.faceCount,
  milliseconds: { ...r.timings, wall },
  iterations: r.solve.iterations,
  planarityMax: r.metrics.planarityMax,
  invalidFaces: r.metrics.selfIntersectingCount,
  surfaceDistanceMax: r.metrics.surfaceDistanceMax,
  peakMemoryMB: memory.heapBytes / 2 ** 20,
}));
phex.dispose();
