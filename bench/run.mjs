// phex — `make bench`: the pipeline natively and in WebAssembly (node), in the same run, case by case.
// Figures only: nothing here passes or fails. Prints a table and writes build/bench/pipeline.json.
//   PHEX_BENCH_QUICK=1        only the 1k and 10k cases
//   PHEX_BENCH_SOLVERS=local  only these solvers (comma-separated)
//   PHEX_BENCH_SIZES=1000     only these face counts (comma-separated; overrides PHEX_BENCH_QUICK)
//   PHEX_BENCH_SURFACES=torus only these surfaces (comma-separated: torus, cyclide, wave-roof.obj, freeform.obj)
//   PHEX_BENCH_REPEAT=5       runs per case up to 10k faces, median reported (one run above 10k)
//   PHEX_BENCH_GLOBAL=0       without the global method's cases (a 20k-triangle upload at 10k and 100k faces)
//   PHEX_BENCH_CERES_100K=1   also the Ceres solvers above 10k faces (planes: ~35 s per Gauss-Newton
//                             iteration and ~1.5 GB at 100k faces natively; volumes far more)
//   PHEX_NATIVE_BIN, PHEX_PKG_DIR, PHEX_BENCH_OUT  other build dirs than build/native/bin, build/pkg,
//                             build/bench (for builds outside the repository's build/)
import { spawnSync } from 'node:child_process';
import { mkdirSync, writeFileSync, readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

const repo = fileURLToPath(new URL('..', import.meta.url));
const cli = join(process.env.PHEX_NATIVE_BIN ?? join(repo, 'build/native/bin'), 'phex');
const outDir = process.env.PHEX_BENCH_OUT ?? join(repo, 'build/bench');
const scratch = mkdtempSync(join(tmpdir(), 'phex-bench-'));
process.on('exit', () => rmSync(scratch, { recursive: true, force: true }));
const sizes = process.env.PHEX_BENCH_SIZES ? process.env.PHEX_BENCH_SIZES.split(',').map(Number)
  : process.env.PHEX_BENCH_QUICK ? [1000, 10000] : [1000, 10000, 100000];
const surfaces = (process.env.PHEX_BENCH_SURFACES ?? 'torus,cyclide,wave-roof.obj,freeform.obj').split(',');

// Every solver side by side where it finishes in reasonable time; the Ceres ones stop at 10k faces
// (their Gauss-Newton steps cost seconds there and about half a minute at 100k, see the README) unless
// PHEX_BENCH_CERES_100K is set.
const solvers = (process.env.PHEX_BENCH_SOLVERS ?? 'local,planes,volumes').split(',');
// Uploaded free-form meshes: analytic height fields sampled finely (120k triangles) as OBJ by phex itself —
// the wave roof (one parabolic curve, curvature lines without umbilics: §5.2's premise) and the two round
// bumps (umbilics inside parabolic rings: no singularity-free conjugate network exists).
const meshFiles = {};
for (const surface of surfaces.filter((s) => s.endsWith('.obj'))) {
  meshFiles[surface] = join(scratch, surface);
  spawnSync(cli, ['triangulate', '--surface', surface.slice(0, -4), '--method', 'lattice', '--faces', '60000', '--out', meshFiles[surface], '--quiet']);
}
// The global method from a 20k-triangle upload (the round bumps sampled by phex's lattice), as the issue of the
// method measures it: 10k and 100k faces end to end, natively and in wasm.
if (process.env.PHEX_BENCH_GLOBAL !== '0') {
  meshFiles['bumps-20k.obj'] = join(scratch, 'bumps-20k.obj');
  spawnSync(cli, ['triangulate', '--surface', 'freeform', '--method', 'lattice', '--faces', '10000', '--out', meshFiles['bumps-20k.obj'], '--quiet']);
}
const cases = [];
if (process.env.PHEX_BENCH_GLOBAL !== '0')
  for (const faces of sizes.filter((f) => f >= 10000)) cases.push({ surface: 'bumps-20k.obj', faces, solver: 'local', method: 'global' });
for (const surface of surfaces)
  for (const faces of sizes)
    for (const solver of solvers)
      if (solver === 'local' || faces <= 10000 || process.env.PHEX_BENCH_CERES_100K) cases.push({ surface, faces, solver });
const isMesh = (c) => c.surface.endsWith('.obj');
// Both sides run each case `repeat` times and report the run with the median total: at 1k faces a run
// takes ~20 ms and single runs on a shared machine scatter by ±50%. Native runs are fresh processes
// after one discarded run (so the binary and the mesh file are in the page cache); wasm runs follow one
// warm-up run of the same case in the same process (see wasm-case.mjs). Runs over 2 s are measured
// once (native: that first run; wasm: one run after the warm-up). Above 10k faces: one run each, the
// wasm warm-up at 10k faces.
const repeatOf = (c) => (c.faces <= 10000 ? Number(process.env.PHEX_BENCH_REPEAT ?? 5) : 1);
const median = (runs) => [...runs].sort((a, b) => a.milliseconds.total - b.milliseconds.total)[(runs.length - 1) >> 1];

// Natively phex splits independent work over the machine's threads (at most 8; `threads`: 0); wasm runs on
// one. The local solver's cases run natively on one thread as well, so that wasm/native also compares the
// same work on one thread.
function native(c, threads = 0) {
  if (c.faces > 10000) return nativeOnce(c, threads);
  const first = nativeOnce(c, threads);
  if (first.error || first.milliseconds.total > 2000) return first;  // long runs scatter little: once
  const runs = Array.from({ length: repeatOf(c) }, () => nativeOnce(c, threads));
  const failed = runs.find((r) => r.error);
  return failed ?? { ...median(runs), totals: runs.map((r) => r.milliseconds.total) };
}

function nativeOnce(c, threads) {
  const report = join(scratch, 'r.json');
  const input = isMesh(c) ? ['--mesh', meshFiles[c.surface]] : ['--surface', c.surface];
  const args = ['run', ...input, ...(c.method ? ['--method', c.method] : []), '--faces', String(c.faces), '--solver', c.solver, '--duality', dualityOf(c),
    '--threads', String(threads), '--report', report, '--quiet'];
  const started = performance.now();
  const p = spawnSync(cli, args, { encoding: 'utf8' });
  const wall = performance.now() - started;
  if (p.status !== 0 && p.status !== 2) return { error: p.stderr.trim() };
  const r = JSON.parse(readFileSync(report, 'utf8'));
  return {
    faces: r.mesh.faces, milliseconds: { ...r.milliseconds, wall }, iterations: r.solver.iterations,
    planarityMax: r.planarity.max, invalidFaces: r.invalidFaces, surfaceDistanceMax: r.surfaceDistance.max,
    peakMemoryMB: r.peakMemoryMB, duality: r.dualityUsed, threads: r.threads,
  };
}

// The default local solver runs as users get it (duality auto: from the tangent dual as well where the solve
// from the Dupin dual stalls); the Ceres solvers, the reference methods, from the Dupin dual alone (§6), so
// that a stalled Ceres solve is not run twice.
function dualityOf(c) {
  return c.solver === 'local' ? 'auto' : 'dupin';
}

function wasm(c) {
  const base = { ...(isMesh(c) ? { meshFile: meshFiles[c.surface], faces: c.faces, solver: c.solver } : c), duality: dualityOf(c),
    ...(c.method ? { method: c.method } : {}) };
  const params = { ...base, repeat: repeatOf(c), ...(c.faces > 10000 ? { warmupFaces: 10000 } : {}) };
  const p = spawnSync('node', ['--no-experimental-fetch', join(repo, 'bench/wasm-case.mjs'), JSON.stringify(params)],
    { encoding: 'utf8', maxBuffer: 1 << 26 });
  if (p.status !== 0) return { error: (p.stderr || p.stdout).trim().split('\n').pop() };
  return JSON.parse(p.stdout.trim().split('\n').pop());
}

const fmt = (x, d = 0) => (x === undefined ? '—' : Number(x).toFixed(d));
const sci = (x) => (x === undefined ? '—' : Number(x).toExponential(1));
const rows = [];
console.log('| surface | faces | solver | where | triangulate | dualize | planarize | measure | total ms | iterations | planarity | invalid | distance/diag | peak MB | wasm/native (1 thread) | wasm first run ms |');
console.log('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|');
for (const c of cases) {
  const n = native(c), one = c.solver === 'local' ? native(c, 1) : undefined, w = wasm(c);
  rows.push({ ...c, native: n, ...(one ? { native1: one } : {}), wasm: w });
  const sides = [[`native, ${n.threads ?? '?'} threads`, n], ...(one && n.threads !== 1 ? [['native, 1 thread', one]] : []), ['wasm', w]];
  for (const [where, r] of sides) {
    const label = c.method ? `${c.surface} (${c.method})` : c.surface;
    if (r.error) { console.log(`| ${label} | ${c.faces} | ${c.solver} | ${where} | error: ${r.error} |`); continue; }
    const ms = r.milliseconds;
    // wasm against native as users get it, and (in brackets) against native on one thread.
    const against = (m) => (m && !m.error ? fmt(ms.total / m.milliseconds.total, 2) : undefined);
    const ratio = where === 'wasm' ? [against(n), one && n.threads !== 1 ? `(${against(one)})` : ''].filter(Boolean).join(' ') : '';
    console.log(`| ${label} | ${r.faces} | ${c.solver} | ${where} | ${fmt(ms.triangulate)} | ${fmt(ms.dualize)} | ${fmt(ms.planarize)} | ${fmt(ms.measure)} | ${fmt(ms.total)} | ${r.iterations}${r.duality === 'tangent' ? ' (tangent)' : ''} | ${sci(r.planarityMax)} | ${r.invalidFaces} | ${sci(r.surfaceDistanceMax)} | ${fmt(r.peakMemoryMB)} | ${ratio} | ${where === 'wasm' ? fmt(r.firstTotal) : ''} |`);
  }
}
// An app editing the parameters of one upload: the runs after the first reuse its surface (read, curvature
// estimated, search structures built once).
const edits = rows.filter((row) => isMesh(row) && !row.wasm.error && row.wasm.surfaceReused);
if (edits.length) {
  console.log('\nwasm, a run on the upload the previous run read (its surface reused), against the table\'s runs without it:');
  console.log('| upload | faces | solver | triangulate ms | total ms | without reuse: triangulate | total |');
  console.log('|---|---|---|---|---|---|---|');
  for (const row of edits)
    console.log(`| ${row.surface} | ${row.wasm.faces} | ${row.solver} | ${fmt(row.wasm.reusedTriangulate)} | ${fmt(row.wasm.reusedTotal)} | ${fmt(row.wasm.milliseconds.triangulate)} | ${fmt(row.wasm.milliseconds.total)} |`);
}
mkdirSync(outDir, { recursive: true });
writeFileSync(join(outDir, 'pipeline.json'), JSON.stringify({ date: new Date().toISOString(), rows }, null, 2));
console.log(`\nwritten: ${join(outDir, 'pipeline.json')}`);
