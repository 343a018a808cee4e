// phex — `make bench`: the pipeline natively and in WebAssembly (node), in the same run, case by case.
// Figures only: nothing here passes or fails. Prints a table and writes build/bench/pipeline.json.
//   PHEX_BENCH_QUICK=1        only the 1k and 10k cases
//   PHEX_BENCH_SOLVERS=local  only these solvers (comma-separated)
import { spawnSync } from 'node:child_process';
import { mkdirSync, writeFileSync, readFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

const repo = fileURLToPath(new URL('..', import.meta.url));
const cli = join(repo, 'build/native/bin/phex');
const scratch = mkdtempSync(join(tmpdir(), 'phex-bench-'));
const sizes = process.env.PHEX_BENCH_QUICK ? [1000, 10000] : [1000, 10000, 100000];

// Every solver side by side where it finishes in reasonable time; the Ceres ones stop at 10k faces
// (their Gauss-Newton steps cost seconds there, see the README's table).
const solvers = (process.env.PHEX_BENCH_SOLVERS ?? 'local,planes,volumes').split(',');
// An uploaded free-form mesh: the free-form height field sampled finely as OBJ by phex itself.
const freeformMesh = join(scratch, 'freeform.obj');
spawnSync(cli, ['triangulate', '--surface', 'freeform', '--method', 'lattice', '--faces', '60000', '--out', freeformMesh, '--quiet']);
const cases = [];
for (const surface of ['torus', 'cyclide', 'freeform.obj'])
  for (const faces of sizes)
    for (const solver of solvers)
      if (solver === 'local' || faces <= 10000) cases.push({ surface, faces, solver });
const isMesh = (c) => c.surface.endsWith('.obj');

function native(c) {
  const report = join(scratch, 'r.json');
  const input = isMesh(c) ? ['--mesh', freeformMesh] : ['--surface', c.surface];
  const args = ['run', ...input, '--faces', String(c.faces), '--solver', c.solver, '--report', report, '--quiet'];
  const started = performance.now();
  const p = spawnSync(cli, args, { encoding: 'utf8' });
  const wall = performance.now() - started;
  if (p.status !== 0 && p.status !== 2) return { error: p.stderr.trim() };
  const r = JSON.parse(readFileSync(report, 'utf8'));
  return {
    faces: r.mesh.faces, milliseconds: { ...r.milliseconds, wall }, iterations: r.solver.iterations,
    planarityMax: r.planarity.max, invalidFaces: r.invalidFaces, surfaceDistanceMax: r.surfaceDistance.max,
    peakMemoryMB: r.peakMemoryMB,
  };
}

function wasm(c) {
  const params = isMesh(c) ? { meshFile: freeformMesh, faces: c.faces, solver: c.solver } : c;
  const p = spawnSync('node', ['--no-experimental-fetch', join(repo, 'bench/wasm-case.mjs'), JSON.stringify(params)],
    { encoding: 'utf8', maxBuffer: 1 << 26 });
  if (p.status !== 0) return { error: (p.stderr || p.stdout).trim().split('\n').pop() };
  return JSON.parse(p.stdout.trim().split('\n').pop());
}

const fmt = (x, d = 0) => (x === undefined ? '—' : Number(x).toFixed(d));
const sci = (x) => (x === undefined ? '—' : Number(x).toExponential(1));
const rows = [];
console.log('| surface | faces | solver | where | triangulate | dualize | planarize | measure | total ms | iterations | planarity | invalid | distance/diag | peak MB | wasm/native |');
console.log('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|');
for (const c of cases) {
  const n = native(c), w = wasm(c);
  rows.push({ ...c, native: n, wasm: w });
  for (const [where, r] of [['native', n], ['wasm', w]]) {
    if (r.error) { console.log(`| ${c.surface} | ${c.faces} | ${c.solver} | ${where} | error: ${r.error} |`); continue; }
    const ms = r.milliseconds;
    const ratio = where === 'wasm' && !n.error ? fmt(ms.total / n.milliseconds.total, 2) : '';
    console.log(`| ${c.surface} | ${r.faces} | ${c.solver} | ${where} | ${fmt(ms.triangulate)} | ${fmt(ms.dualize)} | ${fmt(ms.planarize)} | ${fmt(ms.measure)} | ${fmt(ms.total)} | ${r.iterations} | ${sci(r.planarityMax)} | ${r.invalidFaces} | ${sci(r.surfaceDistanceMax)} | ${fmt(r.peakMemoryMB)} | ${ratio} |`);
  }
}
mkdirSync(join(repo, 'build/bench'), { recursive: true });
writeFileSync(join(repo, 'build/bench/pipeline.json'), JSON.stringify({ date: new Date().toISOString(), rows }, null, 2));
console.log('\nwritten: build/bench/pipeline.json');
