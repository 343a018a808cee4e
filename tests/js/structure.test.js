// phex — the structure on a P-Hex mesh from JavaScript (build/pkg/phex.js in Node, the core in-thread): node axes,
// offsets, planar beams, the solid model for three.js, schedules, and errors that name the option.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { before, test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { createPHex, PHexError, STRUCTURE_OPTIONS } from '../../build/pkg/phex.js';

let phex;
let torus;
let hyperboloid;

before(async () => {
  phex = await createPHex();
  torus = await phex.run({ surface: 'torus', faces: 1000 });
  hyperboloid = await phex.run({ surface: 'hyperboloid', faces: 800 });
});

async function rejection(promise) {
  try {
    await promise;
  } catch (error) {
    return error;
  }
  assert.fail('resolved');
}

const dot = (a, i, b, j) => a[i] * b[j] + a[i + 1] * b[j + 1] + a[i + 2] * b[j + 2];

test('structure gives axes, planar beams and solids ready for three.js; the offset pairs up with the mesh', async () => {
  const { hex } = torus;
  const vertices = hex.positions.length / 3;
  const faces = hex.faceOffsets.length - 1;
  const s = await phex.structure(hex, { offset: 0.02, beamHeight: 0.05, beamWidth: 0.01, panelThickness: 0.004 });
  const { report, nodes, beams, solid, offset } = s;
  assert.equal(report.nodeCount, vertices);
  assert.equal(report.nodesByKind.cone, vertices, 'a closed torus: every node joins three panels');
  assert.equal(report.beamCount, (3 * vertices) / 2);
  assert.deepEqual([report.beamHeight, report.beamWidth, report.panelThickness, report.offset], [0.05, 0.01, 0.004, 0.02]);
  assert.ok(report.offsetRange[0] < -0.05 && report.offsetRange[1] > 0.02, report.offsetRange.join());
  assert.ok(report.beamPlanarityMax <= 1e-9, `beam planarity ${report.beamPlanarityMax}`);
  assert.ok(beams.planarity.every((p) => p <= 1e-9));
  assert.ok(beams.twist.every((t) => t <= 1e-6));
  // Nodes: where the offset goes (position + d axis), and on their planes to the mesh's planarity.
  assert.ok(nodes.positions instanceof Float64Array && nodes.axes instanceof Float64Array);
  for (let i = 0; i < 3 * vertices; i++) {
    assert.ok(Math.abs(nodes.positions[i] - hex.positions[i]) < 1e-7, `node ${Math.floor(i / 3)} moved`);
    assert.ok(Math.abs(offset.positions[i] - (nodes.positions[i] + 0.02 * nodes.axes[i])) < 1e-15);
  }
  assert.deepEqual(offset.faceIndices, hex.faceIndices);
  assert.deepEqual(offset.faceOffsets, hex.faceOffsets);
  // The beam quads: node a, node b, then their back ends 0.05 along the axes.
  for (let b = 0; b < report.beamCount; b += 97) {
    const [na, nb] = [beams.nodes[2 * b], beams.nodes[2 * b + 1]];
    for (let k = 0; k < 3; k++) {
      assert.ok(Math.abs(beams.quads[12 * b + k] - nodes.positions[3 * na + k]) < 1e-15);
      assert.ok(Math.abs(beams.quads[12 * b + 9 + k] - (nodes.positions[3 * na + k] - 0.05 * nodes.axes[3 * na + k])) < 1e-12);
      assert.ok(Math.abs(beams.quads[12 * b + 6 + k] - (nodes.positions[3 * nb + k] - 0.05 * nodes.axes[3 * nb + k])) < 1e-12);
    }
    // Every corner in the beam's plane.
    for (let c = 0; c < 4; c++) assert.ok(Math.abs(dot(beams.quads, 12 * b + 3 * c, beams.planes, 4 * b) - beams.planes[4 * b + 3]) < 1e-12);
  }
  // Solids for a BufferGeometry: single precision, indexed, 12 triangles a beam, each triangle tagged.
  assert.deepEqual(solid.origin, [0, 0, 0]);
  assert.ok(solid.panels.positions instanceof Float32Array && solid.panels.index instanceof Uint32Array);
  assert.equal(solid.panels.count, faces);
  assert.equal(solid.beams.count, report.beamCount);
  assert.equal(solid.beams.index.length, 36 * report.beamCount);
  assert.equal(solid.beams.element.length, 12 * report.beamCount);
  assert.equal(solid.panels.element[solid.panels.element.length - 1], faces - 1);
  assert.equal(solid.axes.positions.length, 6 * vertices);
  assert.ok(solid.panels.index.every((i) => i < solid.panels.positions.length / 3));
});

test('the hyperboloid: boundary beams planar by the boundary rule, the schedules, defaults from the mesh', async () => {
  const { hex } = hyperboloid;
  const s = await phex.structure(hex);
  const { report } = s;
  assert.equal(s.offset, undefined);
  assert.ok(report.boundaryBeams > 50);
  assert.equal(report.boundaryBeamsPlanar, report.boundaryBeams);
  assert.ok(report.boundaryTurnMaxDeg < 30);
  assert.ok(report.nodesByKind.boundary > 0 && report.nodesByKind.corner > 0);
  assert.ok(report.beamPlanarityMax <= 1e-9);
  assert.match(report.notes.join('\n'), /boundary: \d+ of \d+ boundary beams planar/);
  assert.ok(report.beamHeight > 0 && Math.abs(report.beamWidth - report.beamHeight / 4) < 1e-15);
  // Node schedule: a row per node; beam schedule extended with the structure's columns.
  const nodes = (await phex.nodes(hex)).trimEnd().split('\n');
  assert.equal(nodes.length - 1, hex.positions.length / 3);
  assert.match(nodes[0], /^node,kind,faces,x,y,z,axis_x,axis_y,axis_z,scale,panels,axis_face_angles_deg/);
  const plain = (await phex.beams(hex)).trimEnd().split('\n');
  const extended = (await phex.beams(hex, { beamHeight: 0.03 })).trimEnd().split('\n');
  assert.equal(extended.length, plain.length);
  assert.ok(extended[0].startsWith(`${plain[0]},height_a,height_b,plane_nx`));
  // The same beams, nodes and panels (its positions are the nodes on their planes: the last digits may differ).
  const cells = (row, k) => row.split(',').slice(0, 7).filter((c, i) => i !== 3 && i !== 6).join();
  for (let i = 1; i < plain.length; i++) assert.equal(cells(extended[i]), cells(plain[i]));
  const obj = await phex.structureOBJ(hex, { beamHeight: 0.03 });
  assert.equal(obj.split('\n').filter((l) => l.startsWith('o B')).length, report.beamCount);
});

test('a distance out of range rejects naming the option (and the panel), and the next call works', async () => {
  const { hex } = torus;
  const { report } = await phex.structure(hex);
  const cases = [
    [{ beamHeight: 0 }, /beamHeight must be a positive number \(got 0\)/],
    [{ beamHeight: -0.1 }, /beamHeight must be a positive number/],
    [{ beamWidth: -1 }, /beamWidth must be a positive number/],
    [{ panelThickness: 0 }, /panelThickness must be a positive number/],
    [{ offset: 0 }, /offset must be a finite number other than 0/],
    [{ offset: Number.NaN }, /offset must be a finite number/],
    [{ offset: 'wide' }, /offset must be a finite number, got the string "wide"/],
    [{ height: 1 }, /unknown structure option 'height'/],
    [{ offset: 1.5 * report.offsetRange[1] }, /offset = [0-9.e+-]+ is more than the offset can take: the edge between nodes \d+ and \d+ of panel P\d+( \(and P\d+\))? vanishes at face distance/],
    [{ beamHeight: -1.5 * report.offsetRange[0] }, /beamHeight = [0-9.e+-]+ \(face distance -[0-9.e+-]+\) is more than the offset can take/],
  ];
  for (const [options, pattern] of cases) {
    const error = await rejection(phex.structure(hex, options));
    assert.ok(error instanceof PHexError, String(error));
    assert.equal(error.code, 'invalid_parameter', error.message);
    assert.match(error.message, pattern);
  }
  const bad = await rejection(phex.structure({ ...hex, faceOffsets: [0, 3, 6], faceIndices: [0, 1, 2, 0, 1, 3] }));
  assert.equal(bad.code, 'invalid_input');
  assert.match(bad.message, /structure: the edge between vertices 0 and 1 runs the same way in P1 and P2/);
  assert.equal((await phex.structure(hex, { beamHeight: 0.01 })).report.beamCount, report.beamCount);
  assert.deepEqual(STRUCTURE_OPTIONS.map((o) => o.name), ['offset', 'beamHeight', 'beamWidth', 'panelThickness']);
});

const cli = fileURLToPath(new URL('../../build/native/bin/phex', import.meta.url));

test('the wasm structure is the native one: the node schedules agree to the last digit', { skip: !existsSync(cli) && 'no native build' }, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'phex-structure-'));
  try {
    const [obj, nodes] = [join(dir, 'hex.obj'), join(dir, 'nodes.csv')];
    execFileSync(cli, ['run', '--surface', 'cyclide', '--faces', '600', '--out', obj, '--nodes', nodes, '--quiet']);
    const positions = [];
    const faceOffsets = [0];
    const faceIndices = [];
    for (const line of readFileSync(obj, 'utf8').split('\n')) {
      const [kind, ...rest] = line.split(' ');
      if (kind === 'v') positions.push(...rest.map(Number));
      if (kind === 'f') faceIndices.push(...rest.map((v) => Number(v) - 1)), faceOffsets.push(faceIndices.length);
    }
    const mesh = { positions: Float64Array.from(positions), faceOffsets: Uint32Array.from(faceOffsets), faceIndices: Uint32Array.from(faceIndices) };
    assert.equal(await phex.nodes(mesh), readFileSync(nodes, 'utf8'));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
