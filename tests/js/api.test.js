// phex — tests of the JavaScript API (build/pkg/phex.js) in Node, where the core runs in-thread.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { before, test } from 'node:test';
import { createPHex, faceAreas, MESH_FORMATS, meshToOBJ, meshToPLY, PARAMETERS, PHexError, triangulateFaces } from '../../build/pkg/phex.js';

let phex;
let torus; // the default torus result, shared by the tests that only read it
const progress = [];

before(async () => {
  phex = await createPHex();
  torus = await phex.run({ surface: 'torus', faces: 2000 }, { onProgress: (p) => progress.push(p) });
});

async function rejection(params, options) {
  try {
    await phex.run(params, options);
  } catch (error) {
    return error;
  }
  assert.fail(`run(${JSON.stringify(params)}) resolved`);
}

test('the default torus is a planar, valid, hexagon mesh', () => {
  const { hex, metrics, solve, timings } = torus;
  assert.ok(metrics.planarityMax <= 1e-9, `planarity max ${metrics.planarityMax}`);
  assert.ok(solve.converged);
  assert.equal(solve.foldsAllowed, false); // the fold guard never stalled it
  assert.equal(metrics.selfIntersectingCount, 0);
  // Progressive conjugation closes the torus with a zipper row: a few non-hexagons where counts differ.
  assert.ok(metrics.facesBySize['6'] >= 0.9 * metrics.faceCount, JSON.stringify(metrics.facesBySize));
  assert.ok(metrics.faceCount > 1200 && metrics.faceCount < 3200, `face count ${metrics.faceCount}`);

  assert.ok(hex.positions instanceof Float64Array);
  assert.ok(hex.faceOffsets instanceof Uint32Array);
  assert.equal(hex.positions.length, 3 * metrics.vertexCount);
  assert.equal(hex.faceOffsets.length, metrics.faceCount + 1);
  assert.equal(hex.faceIndices.length, hex.faceOffsets[metrics.faceCount]);
  assert.ok(hex.faceIndices.every((v) => v < metrics.vertexCount));
  assert.equal(metrics.planarity.length, metrics.faceCount);
  assert.equal(metrics.selfIntersecting.length, metrics.faceCount);
  assert.equal(Math.max(...metrics.planarity), metrics.planarityMax);
  // Edges under 1 % of the mean edge (over the faces' sides), each once, as counted from the mesh itself.
  const sides = [];
  for (let f = 0; f < metrics.faceCount; ++f)
    for (let k = hex.faceOffsets[f]; k < hex.faceOffsets[f + 1]; ++k) {
      const a = hex.faceIndices[k], b = hex.faceIndices[k + 1 < hex.faceOffsets[f + 1] ? k + 1 : hex.faceOffsets[f]];
      const d = [0, 1, 2].map((i) => hex.positions[3 * a + i] - hex.positions[3 * b + i]);
      sides.push([Math.min(a, b), Math.max(a, b), Math.hypot(...d)]);
    }
  const mean = sides.reduce((sum, [, , l]) => sum + l, 0) / sides.length;
  assert.ok(Math.abs(mean - metrics.edgeLengthMean) <= 1e-9 * mean);
  const short = new Set(sides.filter(([, , l]) => l < 0.01 * mean).map(([a, b]) => `${a},${b}`));
  assert.equal(metrics.shortEdgeCount, short.size);
  assert.equal(torus.triangulation.triangles.length % 3, 0);
  assert.equal(torus.initial.faceOffsets.length, metrics.faceCount + 1);
  for (const stage of ['triangulate', 'dualize', 'planarize', 'measure', 'total']) assert.ok(timings[stage] >= 0, stage);
  assert.equal('ok' in torus, false);
});

// The core is built with WebAssembly exception handling: an engine without it gets an error saying so, before
// any module is loaded (simulated here by a validator that refuses the probe), and never a compile error.
test('an engine without WebAssembly exception handling is refused with code unsupported', async () => {
  assert.ok(WebAssembly.validate(new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0])), 'an empty module validates');
  const validate = WebAssembly.validate;
  WebAssembly.validate = (bytes) => !new Uint8Array(bytes).includes(6) && validate(bytes);  // no `try` (0x06)
  try {
    await assert.rejects(createPHex(), (e) => e instanceof PHexError && e.code === 'unsupported' && /exception handling/.test(e.message));
  } finally {
    WebAssembly.validate = validate;
  }
  const again = await createPHex();  // the real engine has them
  assert.ok((await again.run({ surface: 'torus', faces: 200 })).metrics.faceCount > 0);
  again.dispose();
});

test('progress is reported stage by stage', () => {
  const stages = [...new Set(progress.map((p) => p.stage))];
  for (const stage of ['triangulate', 'dualize', 'planarize', 'measure']) assert.ok(stages.includes(stage), stage);
  for (const p of progress) {
    assert.ok(p.fraction >= 0 && p.fraction <= 1, `fraction ${p.fraction}`);
    assert.equal(typeof p.message, 'string');
  }
});

test('surfaces() lists the analytic surfaces with their parameters', async () => {
  const surfaces = await phex.surfaces();
  const names = surfaces.map((s) => s.name);
  assert.ok(names.includes('torus') && names.includes('sphere'), names.join());
  for (const s of surfaces) {
    assert.ok(s.description.length > 0);
    for (const p of s.parameters) {
      assert.equal(typeof p.name, 'string');
      assert.ok(p.min <= p.default && p.default <= p.max, `${s.name}.${p.name}`);
    }
  }
  surfaces[0].name = 'changed';
  assert.notEqual((await phex.surfaces())[0].name, 'changed', 'callers get their own copy');
  assert.match(phex.version, /^\d+\.\d+\.\d+/);
});

test('bad parameters reject with a PHexError naming them, and phex keeps working', async () => {
  const cases = [
    [{ surface: 'no-such-surface' }, /no-such-surface/],
    [{ surface: 'torus', faces: 0 }, /faces/],
    [{ surface: 'torus', faces: 1e9 }, /faces/],
    [{ surface: 'torus', faces: 12.5 }, /faces/],
    [{ surface: 'torus', faces: '2000' }, /faces/],
    [{ surface: 'torus', tolerance: Number.NaN }, /tolerance/],
    [{ surface: 'torus', duality: 'other' }, /duality/],
    [{ surface: 'torus', surfaceParams: { R: 'big' } }, /surfaceParams\.R/],
    [{ surface: 'torus', surfaceParams: { r: 2 } }, /\br\b/],
    [{ surface: 'torus', facez: 10 }, /facez/],
    [{ surface: 42 }, /surface/],
    [{}, /surface/],
    [null, /parameter object/],
  ];
  for (const [params, message] of cases) {
    const error = await rejection(params);
    assert.ok(error instanceof PHexError, `${JSON.stringify(params)}: ${error}`);
    assert.equal(error.code, 'invalid_parameter', JSON.stringify(params));
    assert.match(error.message, message, JSON.stringify(params));
  }
  const small = await phex.run({ surface: 'sphere', faces: 200 });
  assert.ok(small.metrics.planarityMax <= 1e-9);
  assert.equal(small.metrics.selfIntersectingCount, 0);
});

test('an aborted signal rejects with code cancelled', async () => {
  const controller = new AbortController();
  controller.abort();
  const error = await rejection({ surface: 'torus', faces: 100 }, { signal: controller.signal });
  assert.ok(error instanceof PHexError);
  assert.equal(error.code, 'cancelled');
});

test('runs are queued and each resolves with its own result', async () => {
  const [a, b] = await Promise.all([
    phex.run({ surface: 'torus', faces: 100 }),
    phex.run({ surface: 'sphere', faces: 150 }),
  ]);
  assert.ok(a.metrics.faceCount !== b.metrics.faceCount || a.hex.positions[0] !== b.hex.positions[0]);
  assert.ok(a.metrics.planarityMax <= 1e-9 && b.metrics.planarityMax <= 1e-9);
});

test('triangulateFaces fans each polygon from its first corner', () => {
  const square = { positions: new Float64Array([0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0]), faceOffsets: new Uint32Array([0, 4, 7]), faceIndices: new Uint32Array([0, 1, 2, 3, 1, 4, 2]) };
  const { positions, index, faceOfTriangle } = triangulateFaces(square);
  assert.ok(positions instanceof Float32Array);
  assert.deepEqual([...positions], [...square.positions]);
  assert.deepEqual([...index], [0, 1, 2, 0, 2, 3, 1, 4, 2]);
  assert.deepEqual([...faceOfTriangle], [0, 0, 1]);

  const tri = triangulateFaces(torus.hex);
  assert.equal(tri.faceOfTriangle.length, 4 * torus.metrics.faceCount); // hexagons: 4 triangles each
  assert.equal(tri.index.length, 3 * tri.faceOfTriangle.length);
});

test('triangulateFaces cuts a non-convex face into ears that stay inside it', () => {
  // A hexagon with a notch at corner 4 (2, 0.5), in a tilted plane z = x + y: fanned from corner 0 the triangle
  // (0, 3, 4) would turn the other way and cover the notch.
  const flat = [[0, 0], [2, -1], [4, 0], [4, 2], [2, 0.5], [0, 2]];
  const positions = new Float64Array(flat.flatMap(([x, y]) => [x, y, x + y]));
  const hexagon = { positions, faceOffsets: new Uint32Array([0, 6]), faceIndices: new Uint32Array([0, 1, 2, 3, 4, 5]) };
  const { index, faceOfTriangle } = triangulateFaces(hexagon);
  assert.equal(faceOfTriangle.length, 4);
  const signed = (a, b, c) => ((flat[b][0] - flat[a][0]) * (flat[c][1] - flat[a][1]) - (flat[b][1] - flat[a][1]) * (flat[c][0] - flat[a][0])) / 2;
  let area = 0;
  for (let t = 0; t < 4; t++) {
    const s = signed(index[3 * t], index[3 * t + 1], index[3 * t + 2]);
    assert.ok(s > 0, `triangle ${t} turns the other way (${s})`);
    area += s;
  }
  let polygon = 0;
  for (let i = 0; i < 6; i++) polygon += signed(0, i, (i + 1) % 6);
  assert.ok(Math.abs(area - polygon) < 1e-12, `triangles cover ${area}, the face ${polygon}`);
  // Each corner is used, the notch's included.
  assert.deepEqual([...new Set(index)].sort(), [0, 1, 2, 3, 4, 5]);

  // Corners listed clockwise (the face seen from its back): the triangles turn clockwise too.
  const back = { positions, faceOffsets: new Uint32Array([0, 6]), faceIndices: new Uint32Array([5, 4, 3, 2, 1, 0]) };
  const reversed = triangulateFaces(back).index;
  for (let t = 0; t < 4; t++) assert.ok(signed(reversed[3 * t], reversed[3 * t + 1], reversed[3 * t + 2]) < 0);
});

test('meshToOBJ writes the vertices and 1-based faces', () => {
  const text = meshToOBJ(torus.hex);
  const lines = text.trimEnd().split('\n');
  assert.equal(lines.filter((l) => l.startsWith('v ')).length, torus.metrics.vertexCount);
  const faces = lines.filter((l) => l.startsWith('f '));
  assert.equal(faces.length, torus.metrics.faceCount);
  const first = faces[0].split(' ').slice(1).map(Number);
  const { faceOffsets, faceIndices } = torus.hex;
  assert.deepEqual(first, [...faceIndices.subarray(faceOffsets[0], faceOffsets[1])].map((v) => v + 1));
  assert.equal(Number(lines[1].split(' ')[1]), torus.hex.positions[0], 'full double precision');
});

test('capabilities() says what the core build supports, and unsupported parameters are refused by name', async () => {
  const caps = phex.capabilities();
  for (const key of ['meshInput', 'lowerBound', 'surfacePreview', 'memory']) assert.equal(typeof caps[key], 'boolean', key);
  for (const key of ['meshFormats', 'methods', 'fields']) assert.ok(Array.isArray(caps[key]), key);
  assert.ok(caps.meshFormats.every((f) => MESH_FORMATS.includes(f)));
  caps.methods.push('changed');
  assert.ok(!phex.capabilities().methods.includes('changed'), 'callers get their own copy');

  const cases = [
    [{ surface: 'torus', method: 'progressive' }, 'methods', /method/],
    [{ surface: 'torus', field: 'angle:30' }, 'fields', /field/],
    [{ surface: 'torus', lowerBound: 0.2 }, 'lowerBound', /lowerBound/],
    [{ mesh: new Uint8Array([1, 2, 3]), meshFormat: 'obj' }, 'meshInput', /mesh/],
  ];
  for (const [params, capability, message] of cases) {
    const declared = caps[capability];
    if (Array.isArray(declared) ? declared.length > 0 : declared) continue; // supported: covered elsewhere
    const error = await rejection(params);
    assert.ok(error instanceof PHexError);
    assert.equal(error.code, 'unsupported', JSON.stringify(params));
    assert.match(error.message, message);
  }
});

test('values of the newer parameters are type-checked by name', async () => {
  const cases = [
    [{ surface: 'torus', method: 'magic' }, /method/],
    [{ surface: 'torus', field: 'angle:abc' }, /field/],
    [{ surface: 'torus', field: 7 }, /field/],
    [{ surface: 'torus', lowerBound: Number.POSITIVE_INFINITY }, /lowerBound/],
    [{ mesh: 'v 0 0 0' }, /mesh must be the bytes/],
    [{ mesh: new Uint8Array(4), meshFormat: 'dxf' }, /meshFormat/],
    [{ surface: 'torus', mesh: new Uint8Array(4) }, /either surface or mesh/],
    [{ surface: 'torus', meshFormat: 'obj' }, /need mesh/],
  ];
  for (const [params, message] of cases) {
    const error = await rejection(params);
    assert.ok(error instanceof PHexError, String(error));
    assert.ok(['invalid_parameter', 'unsupported'].includes(error.code), `${JSON.stringify(params)}: ${error.code}`);
    assert.match(error.message, message, JSON.stringify(params));
  }
});

test('PARAMETERS documents every run parameter with its default and range', () => {
  const names = PARAMETERS.map((p) => p.name);
  for (const name of ['faces', 'cell', 'tolerance', 'lambda', 'mu', 'maxIterations', 'duality', 'solver']) assert.ok(names.includes(name), name);
  for (const p of PARAMETERS) {
    assert.ok(p.description.length > 10, p.name);
    if (p.type === 'enum') assert.ok(p.values.includes(p.default), p.name);
    else if (p.type === 'point') assert.equal(p.default, null, p.name);
    else if (p.type !== 'field') assert.ok(p.min <= p.default && p.default <= p.max, p.name);
  }
});

test('memory() reports the wasm heap', async () => {
  const { heapBytes, usedBytes } = await phex.memory();
  assert.ok(Number.isInteger(heapBytes) && heapBytes >= 64 * 2 ** 20, `heap ${heapBytes}`);
  assert.ok(usedBytes === null || (usedBytes > 0 && usedBytes <= heapBytes), `used ${usedBytes}`);
});

test('meshToPLY and meshToOBJ write meshes and triangulations that parse back', () => {
  const ply = meshToPLY(torus.hex, { planarity: torus.metrics.planarity }).trimEnd().split('\n');
  const end = ply.indexOf('end_header');
  assert.ok(ply.includes(`element vertex ${torus.metrics.vertexCount}`));
  assert.ok(ply.includes(`element face ${torus.metrics.faceCount}`));
  assert.equal(ply.length - end - 1, torus.metrics.vertexCount + torus.metrics.faceCount);
  const firstFace = ply[end + 1 + torus.metrics.vertexCount].split(' ').map(Number);
  assert.equal(firstFace[0], 6);
  assert.equal(firstFace.length, 8, 'size, 6 corners, planarity');

  const tri = meshToOBJ(torus.triangulation).split('\n');
  assert.equal(tri.filter((l) => l.startsWith('f ')).length, torus.triangulation.triangles.length / 3);
  assert.throws(() => meshToPLY(torus.hex, { bad: [1, 2] }), /bad/);
});

test('faceAreas gives polygon areas', () => {
  const square = { positions: new Float64Array([0, 0, 0, 2, 0, 0, 2, 3, 0, 0, 3, 0]), faceOffsets: new Uint32Array([0, 4]), faceIndices: new Uint32Array([0, 1, 2, 3]) };
  assert.deepEqual([...faceAreas(square)], [6]);
  const areas = faceAreas(torus.hex);
  assert.equal(areas.length, torus.metrics.faceCount);
  assert.ok(areas.every((a) => a > 0));
  const total = areas.reduce((a, b) => a + b, 0);
  const exact = 4 * Math.PI ** 2 * 1 * 0.4; // the default torus, R = 1, r = 0.4
  assert.ok(Math.abs(total - exact) < 0.05 * exact, `total area ${total}, torus ${exact}`);
});

test('after dispose() every call rejects with code cancelled', async () => {
  const other = await createPHex();
  other.dispose();
  const error = await other.run({ surface: 'torus', faces: 100 }).catch((e) => e);
  assert.equal(error.code, 'cancelled');
});

test("method 'auto' picks the method and field per surface and says which it used", async () => {
  const spec = (await phex.surfaces()).find((s) => s.name === 'elliptic-paraboloid');
  assert.equal(spec.method, 'global');  // rows along its parameter lines left a ragged edge
  const r = await phex.run({ surface: 'elliptic-paraboloid', faces: 600 });
  assert.equal(r.method, 'global');
  assert.equal(r.solve.method, 'local');
  assert.equal(r.field, '');
  assert.ok(r.boundaryOffset.max <= 0.01, JSON.stringify(r.boundaryOffset));
  assert.equal(typeof r.metrics.parabolicFaceCount, 'number');
  assert.ok(r.metrics.interiorHexagonFraction >= 0.9, String(r.metrics.interiorHexagonFraction));
  const vase = await phex.run({ surface: 'vase', faces: 600 });
  assert.equal(vase.method, 'prespecified');
  assert.equal(vase.field, 'principal');
  assert.equal(vase.triangulation.check.invalidStars.length, 0);
  const rows = await phex.run({ surface: 'elliptic-paraboloid', faces: 600, method: 'prespecified', field: 'param' });
  assert.equal(rows.field, 'param');
  assert.equal(rows.triangulation.check.invalidStars.length, 0);
  const named = await phex.run({ surface: 'elliptic-paraboloid', faces: 600, method: 'prespecified', field: 'angle:10' });
  assert.equal(named.field, 'angle:10');
  assert.equal(torus.field, ''); // the torus is laid as a lattice
});

// An nu x nv grid of points point(u, v), u and v in [0, 1], each square cut along one diagonal, as OBJ bytes.
function gridOBJ(nu, nv, point) {
  const lines = [];
  for (let j = 0; j <= nv; j++) for (let i = 0; i <= nu; i++) lines.push(`v ${point(i / nu, j / nv).join(' ')}`);
  for (let j = 0; j < nv; j++) {
    for (let i = 0; i < nu; i++) {
      const a = j * (nu + 1) + i + 1;
      lines.push(`f ${a} ${a + 1} ${a + nu + 2}`, `f ${a} ${a + nu + 2} ${a + nu + 1}`);
    }
  }
  return new TextEncoder().encode(lines.join('\n'));
}

// A developable's P-Hex mesh as §3 has it (as tests/core/pipeline.cpp's checkPlanarAsLaid): quad-shaped
// hexagons planar as laid (no solver iteration), none crossing itself.
function assertPlanarAsLaid(r) {
  assert.equal(r.solve.iterations, 0);
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-12, String(r.metrics.planarityMax));
  assert.ok(r.metrics.interiorHexagonFraction >= 0.99, String(r.metrics.interiorHexagonFraction));
  assert.equal(r.metrics.selfIntersectingCount, 0);
}

test('an uploaded barrel vault (a developable) is laid along its rulings, planar as laid', async () => {
  // Half a cylinder of radius 2 and length 5, jitter-free: the curvature fits keep a trace of the vanishing
  // curvature, which phex takes as 0 (a note says so); each ruling's hexagons share its tangent plane.
  const mesh = gridOBJ(50, 40, (u, v) => [5 * u, 2 * Math.cos(Math.PI * v), 2 * Math.sin(Math.PI * v)]);
  const r = await phex.run({ mesh, meshFormat: 'obj', faces: 1500 });
  assert.ok(r.triangulation.notes.some((note) => /developable/.test(note)), r.triangulation.notes.join('\n'));
  assertPlanarAsLaid(r);
});

test('an uploaded vault on a flat apron (a developable with planar points) is planar as laid', async () => {
  // z = 0 for y < -0.3, then a bend of radius 1.5: the apron's points are planar; they carry the rulings of the
  // bend, so the apron is laid in the same rows, in one system, and its hexagons share its plane.
  const mesh = gridOBJ(100, 100, (u, v) => {
    const x = -1 + 2 * u, y = -1 + 2 * v;
    return [x, y, y < -0.3 ? 0 : 1.5 - Math.sqrt(1.5 * 1.5 - (y + 0.3) * (y + 0.3))];
  });
  const r = await phex.run({ mesh, meshFormat: 'obj', faces: 1000 });
  assert.equal(r.triangulation.systems, 1);
  assertPlanarAsLaid(r);
});

test("an uploaded dome is laid along plane sections under 'auto', and section:DEG is a field of its own", async () => {
  // A paraboloid of revolution: its top is an umbilic, around which its curvature lines turn.
  const mesh = gridOBJ(60, 60, (u, v) => {
    const x = -1 + 2 * u, y = -1 + 2 * v;
    return [x, y, 0.5 * (1 - 0.35 * (x * x + y * y))];
  });
  const auto = await phex.run({ mesh, meshFormat: 'obj', faces: 1200 });
  assert.equal(auto.field, 'section');
  assert.equal(auto.triangulation.check.invalidStars.length, 0);
  assert.ok(auto.metrics.interiorHexagonFraction >= 0.95, String(auto.metrics.interiorHexagonFraction));
  assert.ok(auto.triangulation.notes.some((note) => /plane sections/.test(note) && /umbilic/.test(note)));
  const turned = await phex.run({ mesh, meshFormat: 'obj', faces: 600, method: 'prespecified', field: 'section:30' });
  assert.equal(turned.field, 'section:30');
  for (const field of ['section:abc', 'section:30:1', 'sections']) {
    const error = await rejection({ mesh, meshFormat: 'obj', field });
    assert.ok(error instanceof PHexError, field);
    assert.match(error.message, /field/, field);
  }
});

test('runs on the same upload reuse its surface, with the same result, until clearUploadCache', async () => {
  const mesh = gridOBJ(40, 40, (u, v) => {
    const x = -1 + 2 * u, y = -1 + 2 * v;
    return [x, y, 0.4 - 0.2 * (x * x + y * y)];
  });
  const upload = { mesh, meshFormat: 'obj', meshName: 'cap.obj', faces: 400 };
  await phex.clearUploadCache();
  const first = await phex.run(upload);
  assert.equal(first.surfaceReused, false);
  const again = await phex.run(upload);
  assert.equal(again.surfaceReused, true);
  assert.deepEqual(again.hex.positions, first.hex.positions);
  assert.equal((await phex.run({ surface: 'torus', faces: 300 })).surfaceReused, false);
  assert.equal((await phex.run({ ...upload, faces: 300 })).surfaceReused, true); // an analytic run leaves it
  assert.equal((await phex.run({ ...upload, meshName: 'other.obj' })).surfaceReused, false); // another design
  await phex.clearUploadCache();
  assert.equal((await phex.run({ ...upload, meshName: 'other.obj' })).surfaceReused, false);
});

test('a coarse upload laid finer than its triangles is laid on its smooth refinement, kept with it', async () => {
  // A dome sampled 8 x 8 (128 triangles) at 3000 faces: on its facets the solve stalled at 3e-3.
  const mesh = gridOBJ(8, 8, (u, v) => {
    const x = -1 + 2 * u, y = -1 + 2 * v;
    return [x, y, 0.5 - 0.25 * (x * x + y * y)];
  });
  // (Its rows as auto lays them; at 2000 faces they leave a corner 1.6 panel edges bare, which relay tiles again
  // globally, below.)
  const upload = { mesh, meshFormat: 'obj', meshName: 'sketch.obj', faces: 3000, relay: 'off' };
  await phex.clearUploadCache();
  const r = await phex.run(upload);
  assert.ok(r.triangulation.notes.some((note) => /coarse for this lay/.test(note) && /smooth surface/.test(note)));
  assert.equal(r.solve.converged, true);
  assert.equal(r.metrics.selfIntersectingCount, 0);
  assert.ok(r.metrics.interiorHexagonFraction >= 0.99, String(r.metrics.interiorHexagonFraction));
  assert.ok(r.metrics.surfaceDistanceMax < 0.002, String(r.metrics.surfaceDistanceMax));
  const again = await phex.run(upload);
  assert.equal(again.surfaceReused, true);
  assert.deepEqual(again.hex.positions, r.hex.positions);
  const bare = await phex.run({ ...upload, faces: 2000 });
  const covered = await phex.run({ ...upload, faces: 2000, relay: 'on' });
  assert.deepEqual([covered.relay.globally, covered.relay.kept, covered.method], [true, true, 'global']);
  assert.ok(covered.coverageGap <= 1 && bare.coverageGap > 1, `${bare.coverageGap} -> ${covered.coverageGap}`);
  assert.ok(covered.metrics.interiorHexagonFraction >= 0.95, String(covered.metrics.interiorHexagonFraction));
  await phex.clearUploadCache();
});

test('an upload in site coordinates is computed about its centre and comes back where the file has it', async () => {
  const site = [512345.678, 5432109.876, 250];
  const mesh = gridOBJ(60, 60, (u, v) => {
    const x = -1 + 2 * u, y = -1 + 2 * v;
    return [10 * x + site[0], 10 * y + site[1], 3 * (x * x - y * y) + site[2]];
  });
  const r = await phex.run({ mesh, meshFormat: 'obj', faces: 2000 });
  r.origin.forEach((c, k) => assert.ok(Math.abs(c - site[k]) < 1e-6, `origin ${r.origin}`));
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  for (let k = 0; k < 3; k++) assert.ok(Math.abs(r.hex.positions[k] - site[k]) < 20, `a node at ${r.hex.positions.slice(0, 3)}`);
  assert.ok(r.triangulation.notes.some((note) => /512345\.678, 5432109\.876/.test(note)), r.triangulation.notes.join('\n'));
  const home = await phex.run({ surface: 'torus', faces: 300 });
  assert.deepEqual(home.origin, [0, 0, 0]);
});

test("duality: 'auto' solves from the tangent dual as well where the Dupin one stalls, and says which won", async () => {
  // 2800 asked: its lattice of 2680 faces (the counts' second lay is not needed), whose Dupin solve stalls.
  const auto = await phex.run({ surface: 'cyclide', faces: 2800 });
  assert.equal(auto.duality, 'tangent');
  assert.ok(auto.solve.converged);
  assert.equal(auto.solve.interiorFacesSplit, 0);
  // From the Dupin dual the solve stalls; it reaches the tolerance only by cutting the faces left off.
  const stalled = await phex.run({ surface: 'cyclide', faces: 2800, duality: 'dupin', splitBoundary: 'off' });
  assert.ok(!stalled.solve.converged);
  const dupin = await phex.run({ surface: 'cyclide', faces: 2800, duality: 'dupin' });
  assert.equal(dupin.duality, 'dupin');
  assert.ok(!dupin.solve.converged || dupin.solve.interiorFacesSplit > 0);
  const torus = await phex.run({ surface: 'torus', faces: 800 });
  assert.equal(torus.duality, 'dupin');
});

test("folds: 'prevent' keeps faces simple, 'allow' reaches planarity by folding, anything else is named", async () => {
  // The solver alone: no face cut afterwards (which would cut the folded ones too), Dupin dual only.
  const raw = { surface: 'freeform', method: 'prespecified', faces: 2000, splitBoundary: 'off', duality: 'dupin' };
  const guarded = await phex.run(raw);
  const free = await phex.run({ ...raw, folds: 'allow' });
  assert.ok(free.solve.converged);
  assert.ok(!guarded.solve.converged);
  assert.ok(guarded.metrics.selfIntersectingCount < free.metrics.selfIntersectingCount);
  const error = await rejection({ surface: 'torus', folds: 'maybe' });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /folds/);
});

test("surfaceFit: 'on' shifts the planes closer to the surface, faces stay planar; 'off' does not; anything else is named", async () => {
  const fitted = await phex.run({ surface: 'cyclide', faces: 1000 });
  const plain = await phex.run({ surface: 'cyclide', faces: 1000, surfaceFit: 'off' });
  assert.ok(fitted.solve.surfaceFitted);
  assert.ok(!plain.solve.surfaceFitted);
  assert.ok(fitted.metrics.surfaceDistanceMax < 0.6 * plain.metrics.surfaceDistanceMax);
  assert.ok(fitted.metrics.planarityMax <= 1e-9);
  assert.equal(fitted.metrics.selfIntersectingCount, 0);
  assert.ok(Math.abs(fitted.solve.surfaceDistanceAfter - fitted.metrics.surfaceDistanceMax) < 1e-12);
  const error = await rejection({ surface: 'torus', surfaceFit: 'maybe' });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /surfaceFit/);
});

test("splitBoundary: 'on' cuts boundary panels left off planar and reaches the goal; 'off' does not; anything else is named", async () => {
  // The helicoid at cell 0.043 (about 3800 faces) leaves a few boundary panels where rows reach the rims with
  // no planar shape. One lay each (relay 'off': the trial lays would lay the cut one again).
  const cut = await phex.run({ surface: 'helicoid', cell: 0.043, relay: 'off' });
  const whole = await phex.run({ surface: 'helicoid', cell: 0.043, splitBoundary: 'off', relay: 'off' });
  assert.ok(cut.solve.boundaryPanelsSplit >= 1);
  assert.ok(cut.solve.converged);
  assert.ok(cut.metrics.planarityMax <= 1e-9);
  assert.equal(whole.solve.boundaryPanelsSplit, 0);
  assert.ok(!whole.solve.converged);
  // (The clip's filler triangles, appended after the panels, counted apart, and the panels it removed outside
  // the curve.)
  const { fillers: fc, removed: rc } = cut.boundaryClip, { fillers: fw, removed: rw } = whole.boundaryClip;
  assert.equal(cut.hex.faceOffsets.length - 1 - fc + rc, whole.hex.faceOffsets.length - 1 - fw + rw + cut.solve.boundaryPanelsSplit);
  const error = await rejection({ surface: 'torus', splitBoundary: 'maybe' });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /splitBoundary/);
  const after = await phex.run({ surface: 'torus', faces: 500 });  // the module stays usable
  assert.ok(after.metrics.planarityMax <= 1e-9);
});

test("clipBoundary: anything but 'on' or 'off' is named, and the module stays usable", async () => {
  const error = await rejection({ surface: 'catenoid', clipBoundary: 'maybe' });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /clipBoundary/);
  const after = await phex.run({ surface: 'catenoid', faces: 300, clipBoundary: 'off' });
  assert.equal(after.boundaryClip.panels, 0);
});

test('the bumps are laid in several systems of rows and say so', async () => {
  // No one regular conjugate network reaches both bumps: further systems cover what the first left (Method 2;
  // under auto the bumps are laid globally).
  const r = await phex.run({ surface: 'freeform', method: 'prespecified', faces: 1000 });
  assert.ok(r.triangulation.systems > 1, String(r.triangulation.systems));
  assert.ok(r.triangulation.check.coverage > 0.85, String(r.triangulation.check.coverage));
  assert.ok(r.triangulation.notes.some((n) => /more systems of rows/.test(n)));
  // Laid in several systems, the local solver starts from the tangent dual (fewer faces to cut at the seams).
  assert.equal(r.duality, 'tangent');
  assert.equal(r.metrics.selfIntersectingCount, 0);
  // From the Dupin dual, faces that crossed themselves across the parabolic rings are untangled: none is left folded.
  const dupin = await phex.run({ surface: 'freeform', method: 'prespecified', faces: 1000, duality: 'dupin' });
  assert.ok(dupin.dualUntangled > 0, String(dupin.dualUntangled));
  assert.equal(dupin.metrics.selfIntersectingCount, 0);
  assert.ok(dupin.solve.converged, String(dupin.metrics.planarityMax));
  // Faces the seams leave that only folding would make planar are cut: the mesh reaches the tolerance.
  assert.ok(r.solve.converged, String(r.metrics.planarityMax));
  assert.ok(r.solve.interiorFacesSplit > 8, String(r.solve.interiorFacesSplit));
  // Next to the parabolic rings planar hexagons tend to quads: some edges nearly vanish, and the metrics say how many.
  assert.ok(r.metrics.shortEdgeCount > 0 && r.metrics.shortEdgeCount < 0.05 * r.metrics.faceCount, String(r.metrics.shortEdgeCount));
  const roof = await phex.run({ surface: 'wave-roof', faces: 1000 });
  assert.equal(roof.triangulation.systems, 1);
  assert.equal(typeof roof.dualUntangled, 'number');
});

test('start and direction set where and which way the base curve runs; bad ones are named', async () => {
  const outer = await phex.run({ surface: 'torus', method: 'prespecified', faces: 800, start: [1.4, 0, 0], direction: [0, 1, 0] });
  assert.match(outer.triangulation.notes[0], /L0 closed/);
  assert.ok(!outer.triangulation.notes.some((n) => /start chosen/.test(n)), 'a given start is used as is');
  const auto = await phex.run({ surface: 'torus', method: 'prespecified', faces: 800, start: null });
  assert.match(auto.triangulation.notes[0], /start chosen among/);
  for (const [params, message] of [
    [{ surface: 'torus', start: [1, 2] }, /start must be an array of three finite numbers/],
    [{ surface: 'torus', direction: 'up' }, /direction must be an array/],
    [{ surface: 'torus', direction: [0, 0, Number.NaN] }, /direction must be an array of three finite numbers/],
  ]) {
    const error = await rejection(params);
    assert.equal(error.code, 'invalid_parameter');
    assert.match(error.message, message);
  }
});

test('panels lays every face flat, true to size, as an SVG sheet or a CSV schedule; bad input is named', async () => {
  const { hex, metrics } = torus;
  const svg = await phex.panels(hex);
  assert.match(svg, /^<\?xml/);
  const ids = [...svg.matchAll(/<polygon id="P(\d+)"/g)].map((m) => Number(m[1]));
  assert.deepEqual(ids, Array.from({ length: metrics.faceCount }, (_, i) => i + 1));
  assert.equal((svg.match(/<text /g) ?? []).length, metrics.faceCount);
  assert.doesNotMatch(svg, /<svg [^>]*width=/); // no unit: viewers fit the sheet
  assert.match(await phex.panels(hex, { unit: 'mm', labels: false }), /<svg [^>]*width="[0-9.e+-]+mm"/);

  const rows = (await phex.panels(hex, { format: 'csv' })).trimEnd().split('\n');
  assert.equal(rows.length, metrics.faceCount + 1);
  // Row f: its flat edges as long as the face's edges in space, its area the measured one.
  const { positions, faceOffsets, faceIndices } = hex;
  for (const f of [0, 7, metrics.faceCount - 1]) {
    const cells = rows[f + 1].split(',');
    assert.equal(cells[0], `P${f + 1}`);
    const corners = Array.from(faceIndices.subarray(faceOffsets[f], faceOffsets[f + 1]));
    assert.equal(Number(cells[1]), corners.length);
    assert.ok(Math.abs(Number(cells[2]) - metrics.faceArea[f]) <= 1e-8 * metrics.faceArea[f], `area of P${f + 1}`);
    const edges = cells[11].split(';').map(Number);
    const outline = cells[13].split(';').map((xy) => xy.split(' ').map(Number));
    corners.forEach((v, k) => {
      const w = corners[(k + 1) % corners.length];
      const inSpace = Math.hypot(...[0, 1, 2].map((a) => positions[3 * w + a] - positions[3 * v + a]));
      const [x0, y0] = outline[k];
      const [x1, y1] = outline[(k + 1) % corners.length];
      assert.ok(Math.abs(edges[k] - inSpace) <= 1e-9 * inSpace);
      assert.ok(Math.abs(Math.hypot(x1 - x0, y1 - y0) - inSpace) <= 1e-8 * inSpace, `flat edge ${k} of P${f + 1}`);
    });
  }

  const failure = async (mesh, options) => {
    try {
      await phex.panels(mesh, options);
    } catch (error) {
      return error;
    }
    assert.fail('panels resolved');
  };
  let error = await failure(hex, { format: 'dxf' });
  assert.ok(error instanceof PHexError);
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /format/);
  error = await failure(hex, { unit: 'ft' });
  assert.equal(error.code, 'invalid_parameter');
  error = await failure(hex, { gap: -1 });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /gap/);
  error = await failure(hex, { width: Number.NaN });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /width/);
  error = await failure(hex, { labels: 'yes' });
  assert.equal(error.code, 'invalid_parameter');
  assert.match(error.message, /labels/);
  const broken = { ...hex, faceIndices: Uint32Array.from(hex.faceIndices, (v, i) => (i === 8 ? 1e6 : v)) };
  error = await failure(broken);
  assert.equal(error.code, 'invalid_input');
  assert.match(error.message, /face 1 \(P2\) names vertex 1000000/);
  error = await failure({ positions: new Float64Array(4), faceOffsets: [0], faceIndices: [] });
  assert.equal(error.code, 'invalid_input');
  assert.match(error.message, /multiple of 3/);
  error = await failure(null);
  assert.equal(error.code, 'invalid_input');
  // The instance keeps working.
  assert.equal((await phex.panels(hex, { format: 'csv' })).trimEnd().split('\n').length, metrics.faceCount + 1);
});

test('beams lists every edge once with its panels and fold; bad meshes are named', async () => {
  const { hex } = torus;
  const rows = (await phex.beams(hex)).trimEnd().split('\n').map((r) => r.split(','));
  assert.deepEqual(rows[0].slice(0, 7), ['beam', 'node_a', 'node_b', 'length', 'panel_left', 'panel_right', 'fold_deg']);
  const vertices = hex.positions.length / 3;
  assert.equal(rows.length - 1, (3 * vertices) / 2); // closed, three beams at each node
  const { positions } = hex;
  let ridges = 0;
  let valleys = 0;
  for (const row of rows.slice(1)) {
    const [a, b] = [Number(row[1]) - 1, Number(row[2]) - 1];
    const length = Math.hypot(...[0, 1, 2].map((k) => positions[3 * a + k] - positions[3 * b + k]));
    assert.ok(Math.abs(Number(row[3]) - length) <= 1e-9 * length);
    assert.match(row[4], /^P\d+$/);
    assert.match(row[5], /^P\d+$/);
    if (Number(row[6]) > 0) ridges++;
    else valleys++;
  }
  // The torus' outer half is convex (ridges only); its inner half (K < 0) folds both ways.
  assert.ok(ridges > valleys && valleys > 0, `${ridges} ridges, ${valleys} valleys`);
  const doubled = { ...hex, faceOffsets: [0, 3, 6], faceIndices: [0, 1, 2, 0, 1, 3] };
  let error;
  try {
    await phex.beams(doubled);
  } catch (e) {
    error = e;
  }
  assert.equal(error?.code, 'invalid_input');
  assert.match(error.message, /runs the same way in P1 and P2/);
});
