// Benchmark: the structure on a P-Hex mesh in WebAssembly (node, the core in-thread, as phex.structure() gives it
// to a page: the mesh copied in, the typed arrays copied out), next to the same process's pipeline time for that
// mesh. Figures only. Usage: node --no-experimental-fetch bench/structure-wasm.mjs [faces, default 10000]
import { createPHex } from '../build/pkg/phex.js';

const faces = Number(process.argv[2] ?? 10000);
const phex = await createPHex();
const median = (xs) => [...xs].sort((a, b) => a - b)[(xs.length - 1) >> 1];
console.log('| surface | faces | pipeline ms | structure ms (wasm, API call) | beams/boundary planar |');
console.log('|---|---|---|---|---|');
for (const surface of ['torus', 'cyclide', 'hyperboloid']) {
  await phex.run({ surface, faces }); // warm-up: V8 tiers the code up
  const started = performance.now();
  const r = await phex.run({ surface, faces });
  const pipeline = performance.now() - started;
  const options = { offset: 0.05 * r.metrics.edgeLengthMean };
  await phex.structure(r.hex, options);
  const runs = [];
  let s;
  for (let i = 0; i < 7; i++) {
    const t = performance.now();
    s = await phex.structure(r.hex, options);
    runs.push(performance.now() - t);
  }
  console.log(`| ${surface} | ${r.metrics.faceCount} | ${pipeline.toFixed(0)} | ${median(runs).toFixed(1)} | ${s.report.boundaryBeamsPlanar} of ${s.report.boundaryBeams} |`);
}
phex.dispose();
