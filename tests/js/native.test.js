// phex — the wasm build must compute what the native build computes (both are built without FMA).
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { createPHex } from '../../build/pkg/phex.js';
import { blobOFF } from './meshes.js';

const cli = fileURLToPath(new URL('../../build/native/bin/phex', import.meta.url));
const RELATIVE_TOLERANCE = 1e-9;

function parseObj(text) {
  const positions = [];
  const faces = [];
  for (const line of text.split('\n')) {
    const [kind, ...rest] = line.trim().split(/\s+/);
    if (kind === 'v') positions.push(...rest.map(Number));
    else if (kind === 'f') faces.push(rest.map((v) => Number(v.split('/')[0]) - 1));
  }
  return { positions, faces };
}

// Runs the native CLI with `args` (writing OBJ) and wasm with `params`, and asserts the same faces and the
// same vertices to round-off.
async function assertSameRun(args, params) {
  const dir = mkdtempSync(join(tmpdir(), 'phex-native-'));
  try {
    const out = join(dir, 'hex.obj');
    execFileSync(cli, ['run', ...args, '--quiet', '--out', out]);
    const native = parseObj(readFileSync(out, 'utf8'));

    const phex = await createPHex();
    const { hex } = await phex.run(params);
    phex.dispose();
    const faces = [];
    for (let f = 0; f + 1 < hex.faceOffsets.length; f++) faces.push([...hex.faceIndices.subarray(hex.faceOffsets[f], hex.faceOffsets[f + 1])]);

    assert.deepEqual(faces, native.faces, 'same faces');
    assert.equal(hex.positions.length, native.positions.length, 'same vertex count');
    const scale = Math.max(...native.positions.map(Math.abs));
    let worst = 0;
    for (let i = 0; i < native.positions.length; i++) worst = Math.max(worst, Math.abs(hex.positions[i] - native.positions[i]));
    assert.ok(worst <= RELATIVE_TOLERANCE * scale, `largest coordinate difference ${worst} (model size ${scale})`);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

const noCli = !existsSync(cli) && 'build/native/bin/phex is not built';

test('wasm and native CLI give the same torus', { skip: noCli }, async () => {
  await assertSameRun(['--surface', 'torus', '--faces', '2000'], { surface: 'torus', faces: 2000 });
});

// An uploaded mesh goes through the curvature estimate (jet fits), closest-point queries and the start choice's
// trial lays, where a last-bit difference between the platforms' libm or Eigen's summation order would
// change the laying.
// An analytic surface's lattice at `faces`, written by the native CLI as an OBJ upload in a scratch folder: `use`
// gets its path and bytes; the folder goes afterwards.
async function withLatticeUpload(surface, faces, use) {
  const dir = mkdtempSync(join(tmpdir(), 'phex-native-mesh-'));
  try {
    const mesh = join(dir, `${surface}.obj`);
    execFileSync(cli, ['triangulate', '--surface', surface, '--method', 'lattice', '--faces', String(faces), '--quiet', '--out', mesh]);
    await use(mesh, new Uint8Array(readFileSync(mesh)));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

test('wasm and native CLI tile the same uploaded mesh alike', { skip: noCli }, async () => {
  await withLatticeUpload('wave-roof', 4000, (mesh, bytes) =>
    assertSameRun(['--mesh', mesh, '--faces', '1000'], { mesh: bytes, meshFormat: 'obj', faces: 1000 }));
});

// The global method's field, lattice and extraction round to lattice points and pick among candidates: a last-bit
// difference between the builds would change the mesh. The analytic surfaces' trigonometry is computed with
// +, -, *, / alone (portable_math.hpp: with libm's it was 660 faces natively and 652 in wasm for 600 asked).
test('wasm and native CLI give the same torus by the global method', { skip: noCli }, async () => {
  await assertSameRun(['--surface', 'torus', '--faces', '600', '--method', 'global'], { surface: 'torus', faces: 600, method: 'global' });
});

test('wasm and native CLI give the same upload by the global method', { skip: noCli }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'phex-native-global-'));
  try {
    const file = join(dir, 'blob.off');
    const bytes = blobOFF(4);
    writeFileSync(file, bytes);
    await assertSameRun(['--mesh', file, '--faces', '600', '--method', 'global'], { mesh: bytes, meshFormat: 'off', faces: 600, method: 'global' });
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

// A fine upload is remeshed to the field's edge before the global method lays its field (remesh.cpp, thinned):
// collapses in buckets of length, flips and a relaxation onto the surface, the same in both builds.
test('wasm and native CLI give the same fine upload, remeshed for the global method', { skip: noCli }, async () => {
  await withLatticeUpload('hyperbolic-paraboloid', 20000, async (mesh, bytes) => {
    const params = { mesh: bytes, meshFormat: 'obj', faces: 500, method: 'global' };
    const phex = await createPHex();
    const r = await phex.run(params);
    phex.dispose();
    assert.ok(r.triangulation.notes.some((note) => /remeshed to \d+ at its edge/.test(note)), r.triangulation.notes.join('\n'));
    await assertSameRun(['--mesh', mesh, '--faces', '500', '--method', 'global'], params);
  });
});

// An uneven upload coarser than the field mesh (slivers ten times as long as wide over a paraboloid) is remeshed at
// two field-mesh edges and split 2 x 2 (remesh.cpp, thinnedSplit; its split points' closest points checked
// for folds, untangleSplit): the same in both builds.
test('wasm and native CLI give the same uneven upload, remeshed at twice the field edge and split', { skip: noCli }, async () => {
  const lines = [];
  const nx = 10, ny = 100;
  for (let j = 0; j <= ny; j++) {
    for (let i = 0; i <= nx; i++) {
      const x = -1 + (2 * i) / nx, y = -1 + (2 * j) / ny;
      lines.push(`v ${x} ${y} ${0.3 * (x * x + y * y)}`);
    }
  }
  for (let j = 0; j < ny; j++) {
    for (let i = 0; i < nx; i++) {
      const a = j * (nx + 1) + i + 1;
      lines.push(`f ${a} ${a + 1} ${a + nx + 2}`, `f ${a} ${a + nx + 2} ${a + nx + 1}`);
    }
  }
  const bytes = new TextEncoder().encode(lines.join('\n'));
  const dir = mkdtempSync(join(tmpdir(), 'phex-native-uneven-'));
  try {
    const file = join(dir, 'slivers.obj');
    writeFileSync(file, bytes);
    const params = { mesh: bytes, meshFormat: 'obj', faces: 780, method: 'global' };
    const phex = await createPHex();
    const r = await phex.run(params);
    phex.dispose();
    assert.ok(r.triangulation.notes.some((note) => /at 2 times its edge and split 2 x 2/.test(note)), r.triangulation.notes.join('\n'));
    await assertSameRun(['--mesh', file, '--faces', '780', '--method', 'global'], params);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

// A noisy upload whose first lay falls short is laid again with the repairs of a smooth upload (fairness, changes at
// folded boundary panels, dislocation glides, relay and trial lays): the same mesh in both builds, and the report
// says which lay was kept. PH-CPF's intersection shell at 1000 faces (tests/data, CC BY-SA 4.0), laid on its
// refinement (noisy too), reaches a P-Hex mesh so.
// A model of tests/data run in wasm on a fresh instance: its path, the params and the result.
async function runDataModel(name, faces, options = {}) {
  const file = fileURLToPath(new URL(`../data/${name}`, import.meta.url));
  const params = { mesh: new Uint8Array(readFileSync(file)), meshFormat: 'off', meshName: name, faces, ...options };
  const phex = await createPHex();
  try {
    return { file, params, r: await phex.run(params) };
  } finally {
    phex.dispose();
  }
}

test('wasm and native CLI give the same noisy upload, laid again with the repairs', { skip: noCli }, async () => {
  const { file, params, r } = await runDataModel('phcpf_intersection.off', 1000);
  // Laid on its refinement by the smooth blend of its vertices' jets (MeshSurface::Blend::Smooth), the same in both.
  assert.ok(r.triangulation.notes.some((note) => /onto the smooth blend of the cubic fits around its vertices/.test(note)), r.triangulation.notes.join('\n'));
  assert.ok(r.relay.noisyRepairs && r.relay.noisyRepairsKept, JSON.stringify(r.relay));
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  assert.ok(r.triangulation.notes.some((note) => /laid again with them, as a smooth upload is, it reached one/.test(note)), r.triangulation.notes.join('\n'));
  await assertSameRun(['--mesh', file, '--faces', '1000'], params);
});

// Where the lay kept reached a P-Hex mesh only with many nodes of four from cuts (PH-CPF's car at 1000 faces, tests/data,
// CC BY-SA 4.0, laid on its refinement: its relay cut faces making 184 such nodes), all is laid again with the rounds
// against folds on more folds: planar in both builds with no face cut, the same mesh, and a note says so.
test('wasm and native CLI give the same car, laid again with the rounds against folds where the lay kept cut many faces', { skip: noCli }, async () => {
  const { file, params, r } = await runDataModel('phcpf_car_r.off', 1000);
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  assert.equal(r.metrics.selfIntersectingCount, 0);
  assert.equal(r.solve.interiorFacesSplit, 0);
  assert.ok(r.triangulation.notes.some((note) => /the lay kept reached a P-Hex mesh only with \d+ nodes of four .* it reached one/.test(note)), r.triangulation.notes.join('\n'));
  await assertSameRun(['--mesh', file, '--faces', '1000'], params);
});
