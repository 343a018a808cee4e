// Uploaded mesh files through the JS library: every defect is a PHexError naming the file and the defect
// or its position, and the instance keeps working afterwards.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { createPHex, PHexError } from '../../build/pkg/phex.js';

const phex = await createPHex({ worker: false });
const text = (s) => new TextEncoder().encode(s);

function binaryStl(triangles, declared = triangles.length) {
  const bytes = new Uint8Array(84 + 50 * triangles.length);
  const view = new DataView(bytes.buffer);
  view.setUint32(80, declared, true);
  triangles.forEach((tri, i) => tri.flat().forEach((x, k) => view.setFloat32(84 + 50 * i + 12 + 4 * k, x, true)));
  return bytes;
}

// A closed octahedron: a small valid mesh to start from.
const octahedron = 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n' +
  'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n';

const cases = [
  ['index out of range', 'bad-index.obj', 'obj', text('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n'), /bad-index\.obj.*line 4/],
  ['NaN coordinate', 'nan.obj', 'obj', text('v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n'), /nan\.obj.*line 2/],
  ['zero faces', 'empty.obj', 'obj', text('v 0 0 0\nv 1 0 0\n'), /empty\.obj/],
  ['wrong counts', 'short.off', 'off', text('OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n'), /short\.off/],
  ['truncated binary STL', 'cut.stl', 'stl', binaryStl([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], 5), /cut\.stl/],
  ['text in a binary PLY', 'mixed.ply', 'ply',
    text('ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0 3 0 1 2\n'),
    /mixed\.ply/],
  ['non-manifold edge', 'fan.obj', 'obj', text('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n'), /fan\.obj.*(manifold|edge)/i],
  ['only degenerate triangles', 'flat.obj', 'obj', text('v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n'), /flat\.obj/],
];

for (const [what, name, format, bytes, pattern] of cases) {
  test(`a mesh file with ${what} is refused with a message naming it`, async () => {
    for (const call of [() => phex.run({ mesh: bytes, meshFormat: format, meshName: name }),
                        () => phex.surfacePreview({ mesh: bytes, meshFormat: format, meshName: name })]) {
      await assert.rejects(call(), (e) => {
        assert.ok(e instanceof PHexError, `${what}: ${e}`);
        assert.equal(e.code, 'invalid_input', `${what}: ${e.message}`);
        assert.match(e.message, pattern);
        return true;
      });
    }
  });
}

test('after refused files a good mesh still works: the octahedron as a subdivision control', async () => {
  const r = await phex.run({ mesh: text(octahedron), meshFormat: 'obj', meshName: 'octahedron.obj', method: 'subdivision', faces: 300 });
  assert.ok(r.metrics.planarityMax <= 1e-9);
  assert.equal(r.metrics.selfIntersectingCount, 0);
  const preview = await phex.surfacePreview({ mesh: text(octahedron), meshFormat: 'obj', meshName: 'octahedron.obj' });
  assert.equal(preview.k1.length, 6);
});

// The files fuzzing found (tests/fuzz/regressions.json): each refused at once, naming its problem.
const regressions = Object.entries(JSON.parse(readFileSync(new URL('../fuzz/regressions.json', import.meta.url)))).filter(([f]) => f !== '//');

for (const [file, message] of regressions) {
  test(`fuzzing's ${file} is refused within a second, naming the problem`, async () => {
    const bytes = new Uint8Array(readFileSync(new URL(`../fuzz/regressions/${file}`, import.meta.url)));
    const started = performance.now();
    await assert.rejects(phex.run({ mesh: bytes, meshFormat: file.split('.').pop(), meshName: file }), (e) => {
      assert.ok(e instanceof PHexError, String(e));
      assert.equal(e.code, 'invalid_input', e.message);
      assert.ok(e.message.includes(`'${file}'`) && e.message.includes(message), e.message);
      return true;
    });
    assert.ok(performance.now() - started < 1000, `${file}: ${performance.now() - started} ms`);
  });
}

test('a trap or an abort in the core (a file that slips through) is a PHexError, and the next run works', async () => {
  for (const kind of ['unreachable', 'abort', 'memory']) {
    await assert.rejects(phex.debugTrap(kind), (e) => {
      assert.ok(e instanceof PHexError, `${kind}: ${e}`);
      assert.equal(e.code, 'internal');
      assert.match(e.message, /the phex core failed/);
      return true;
    });
    const r = await phex.run({ mesh: text(octahedron), meshFormat: 'obj', meshName: 'octahedron.obj', method: 'subdivision', faces: 100 });
    assert.ok(r.metrics.planarityMax <= 1e-9, kind);
  }
});
