// phex — method 'global' through the JS API (build/pkg/phex.js): any surface tiled along a 6-fold field, its
// singular points returned, its options checked by name.
// Run: node --no-experimental-fetch --test tests/js/   (after `make wasm`)
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { createPHex, meshToOBJ, PARAMETERS, PHexError } from '../../build/pkg/phex.js';
import { assertClosedDual, assertNoCut, assertSingularities, blobOFF, hexagonDefect } from './meshes.js';

let phex;
before(async () => {
  phex = await createPHex();
});
after(() => phex.dispose());

test("the API offers method 'global' and documents its options with their defaults and ranges", () => {
  const caps = phex.capabilities();
  assert.ok(caps.methods.includes('global'), caps.methods.join());
  assert.equal(caps.globalOptions, true);
  const spec = Object.fromEntries(PARAMETERS.map((p) => [p.name, p]));
  assert.ok(spec.method.values.includes('global'));
  for (const [name, value, min, max] of [['anisotropy', 2, 1, 8], ['alignment', 3, 0, 10], ['curvatureSizing', 0, 0, 1], ['curvatureFloor', 0.25, 0.01, 1], ['fairness', 0.03, 0, 1]]) {
    assert.deepEqual([spec[name].default, spec[name].min, spec[name].max], [value, min, max], name);
    assert.match(spec[name].description, /global/, name);
  }
  assert.deepEqual([spec.foldFlips.default, spec.foldFlips.values, spec.foldFlips.requires], ['on', ['on', 'off'], 'globalOptions']);
  assert.match(spec.foldFlips.description, /global/);
  assert.deepEqual([spec.dislocations.default, spec.dislocations.values, spec.dislocations.requires], ['cancel', ['cancel', 'keep'], 'globalOptions']);
  assert.match(spec.dislocations.description, /global/);
  assert.deepEqual([spec.principalField.default, spec.principalField.values, spec.principalField.requires], ['try', ['try', 'off'], 'globalOptions']);
  assert.match(spec.principalField.description, /global/);
  assert.deepEqual([spec.relay.default, spec.relay.values, spec.relay.requires], ['on', ['on', 'off'], 'globalOptions']);
  assert.match(spec.relay.description, /global/);
});

// The core's global method is still being tuned (issue 31): it reaches planarity by cutting some faces in two.
// What it returns is checked for consistency with its report (assertClosedDual); the goal of no cut is a todo
// test, reported, not failing, until the core meets it.
let torus;  // the global torus, shared
const globalTorus = () => (torus ??= phex.run({ surface: 'torus', faces: 600, method: 'global' }));

test("method 'global' tiles the torus: a closed planar P-Hex mesh, singular points adding up to 0 (genus 1)", async () => {
  const r = await globalTorus();
  assert.equal(r.method, 'global');
  const summary = JSON.stringify({ faces: r.metrics.faceCount, bySize: r.metrics.facesBySize, planarity: r.metrics.planarityMax });
  assert.ok(r.metrics.faceCount > 450 && r.metrics.faceCount < 800, summary);
  assertClosedDual(r, 1);
  assert.equal(r.metrics.selfIntersectingCount, 0, summary);
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, summary);

  const sum = assertSingularities(r.triangulation.singularities);
  assert.equal(sum, 0, `indices ${[...r.triangulation.singularities.index]}`);
  // Each singular point lies on the torus (R 1, r 0.4 by default), within a cell of it.
  const { positions } = r.triangulation.singularities;
  const cell = r.triangulation.check.edgeMean;
  for (let i = 0; i < positions.length; i += 3) {
    const [x, y, z] = positions.subarray(i, i + 3);
    const off = Math.abs(Math.hypot(Math.hypot(x, y) - 1, z) - 0.4);
    assert.ok(off < cell, `singular point ${i / 3} is ${off} off the torus`);
  }
  // Its field, drawn in the triangulation view, comes as polylines like the other methods' field lines.
  const { fieldLines } = r.triangulation;
  assert.equal(fieldLines.positions.length, 3 * fieldLines.offsets.at(-1));
});

test("method 'global' on the torus: no face cut, every node of three faces (issue 31)", async () => {
  assertNoCut(await globalTorus());
});

let blob;  // the closed genus-0 upload's run, shared
const globalBlob = () => (blob ??= phex.run({ mesh: blobOFF(), meshFormat: 'off', meshName: 'blob.off', method: 'global', faces: 400 }));

test('a closed genus-0 upload: singular indices add up to 12, as do the P-Hex faces short of six corners (less the cuts)', async () => {
  const r = await globalBlob();
  const { index } = r.triangulation.singularities;
  const sum = assertSingularities(r.triangulation.singularities);
  assert.equal(sum, 12, `indices ${[...index]}`);
  assertClosedDual(r, 0);
  assert.equal(r.metrics.selfIntersectingCount, 0);
  // No hole: every vertex of the upload within one mean panel edge of the P-Hex mesh.
  assert.ok(r.coverageGap > 0 && r.coverageGap <= 1, `coverage gap ${r.coverageGap}`);
  assert.ok(r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));

  // The same blob in site coordinates: its singular points come back beside its mesh, in the file's coordinates.
  const site = [512345.678, 5432109.876, 250];
  const far = await phex.run({ mesh: blobOFF(3, site), meshFormat: 'off', meshName: 'blob-site.off', method: 'global', faces: 400 });
  assert.ok(far.origin.every((c, k) => Math.abs(c - site[k]) < 1), `origin ${far.origin}`);
  assert.equal(assertSingularities(far.triangulation.singularities), 12);
  const { positions } = far.triangulation.singularities;
  for (let i = 0; i < positions.length; i += 3) {
    const d = Math.hypot(...[0, 1, 2].map((k) => positions[i + k] - site[k]));
    assert.ok(d < 2, `singular point ${i / 3} at ${positions.subarray(i, i + 3)}: ${d} from the blob's centre`);
  }
  await phex.clearUploadCache();
});

test('a closed genus-0 upload: no face cut, every node of three faces, Σ (6 − corners) = 12 on the P-Hex mesh (issue 31)', async () => {
  const r = await globalBlob();
  assertNoCut(r);
  assert.equal(hexagonDefect(r.hex), 12);
});

test('boundary nodes end on the surface\'s boundary curve (a clean edge), and a closed surface has none', async () => {
  const open = await phex.run({ surface: 'catenoid', method: 'global', faces: 600 });
  assert.ok(open.solve.converged);
  assert.ok(open.solve.boundaryNodesPlaced > 30, String(open.solve.boundaryNodesPlaced));
  assert.ok(open.boundaryOffset.nodes > 30 && open.boundaryOffset.max <= 1e-3, JSON.stringify(open.boundaryOffset));
  // The boundary panels clipped to the curve: planar, their outline within a tenth of an edge of the curve.
  assert.ok(open.boundaryClip.panels > 30 && open.boundaryClip.skipped === 0, JSON.stringify(open.boundaryClip));
  assert.ok(open.boundaryClip.nodesAdded > 30 && open.boundaryClip.gapMax < 0.1, JSON.stringify(open.boundaryClip));
  assert.ok(open.metrics.planarityMax <= 1e-9);
  const raw = await phex.run({ surface: 'catenoid', method: 'global', faces: 600, surfaceFit: 'off', clipBoundary: 'off' });
  assert.equal(raw.solve.boundaryNodesPlaced, 0);
  assert.ok(raw.boundaryOffset.median > 0.01, JSON.stringify(raw.boundaryOffset));
  assert.equal(raw.boundaryClip.panels, 0);
  assert.equal(raw.hex.faceOffsets.length, open.hex.faceOffsets.length);  // the same panels, their edges clipped
  const r = await globalBlob();
  assert.deepEqual(r.boundaryOffset, { max: 0, median: 0, nodes: 0 });
  assert.equal(r.boundaryClip.panels, 0);
});

test('a sliver of a boundary panel cut against a fold, lying outside the curve, is removed and its neighbours clipped', async () => {
  // The hyperbolic paraboloid laid globally at 1000 faces: one boundary panel cut in two, the piece beyond the curve
  // (that lay: relay 'off', as the trial lays would replace it by one without the cut; foldFlips 'off', as the
  // rounds against folds now drop that panel's vertex, and nothing is cut; dislocations 'keep', the lattice where the
  // case was found: with its dislocations cancelled it falls otherwise and no panel is cut there).
  const r = await phex.run({ surface: 'hyperbolic-paraboloid', method: 'global', faces: 1000, relay: 'off', foldFlips: 'off', dislocations: 'keep' });
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9);
  // (Since cut boundary panels are left out before the clip where it clips as well, the whole panel goes, its two
  // pieces, before the clip sees the sliver: `cutDropped`.)
  assert.equal(r.boundaryClip.removed + r.boundaryClip.cutDropped, 1, JSON.stringify(r.boundaryClip));
  assert.equal(r.boundaryClip.skipped, 0, JSON.stringify(r.boundaryClip));
  assert.equal(r.metrics.boundaryFace.length, r.hex.faceOffsets.length - 1);
  const off = await phex.run({ surface: 'hyperbolic-paraboloid', method: 'global', faces: 1000, clipBoundary: 'off', relay: 'off',
    foldFlips: 'off', dislocations: 'keep' });
  assert.equal(off.boundaryClip.removed, 0);
  assert.equal(off.boundaryClip.cutDropped, 0);
  assert.equal(off.solve.boundaryPanelsSplit, 1);
  const gone = r.boundaryClip.removed + 2 * r.boundaryClip.cutDropped;  // the sliver, or both pieces of the panel
  assert.equal(off.hex.faceOffsets.length - 1 - gone, r.hex.faceOffsets.length - 1 - r.boundaryClip.fillers);
});

test('where two boundary panels meet along the curve, a filler triangle closes the tooth (a clean edge on the bumps)', async () => {
  // The bumps laid globally at 2000 faces: along one side the panels' shared nodes stayed 0.26-0.42 edges inside
  // the curve (their shared edges run along it); each gets a filler triangle, and the outline follows the curve.
  const r = await phex.run({ surface: 'freeform', method: 'global', faces: 2000 });
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9);
  assert.ok(r.boundaryClip.fillers >= 8, JSON.stringify(r.boundaryClip));
  assert.ok(r.boundaryOffset.max < 0.01, JSON.stringify(r.boundaryOffset));
  // The fillers come last: triangles on the boundary.
  const { faceOffsets } = r.hex;
  const faces = faceOffsets.length - 1;
  for (let f = faces - r.boundaryClip.fillers; f < faces; f++) {
    assert.equal(faceOffsets[f + 1] - faceOffsets[f], 3);
    assert.equal(r.metrics.boundaryFace[f], 1);
  }
  const raw = await phex.run({ surface: 'freeform', method: 'global', faces: 2000, clipBoundary: 'off' });
  assert.ok(raw.boundaryOffset.max > 0.25, JSON.stringify(raw.boundaryOffset));
});

test('the other methods return no singular points', async () => {
  const r = await phex.run({ surface: 'sphere', faces: 200 });
  assert.notEqual(r.method, 'global');
  assert.equal(assertSingularities(r.triangulation.singularities), 0);
  assert.equal(r.triangulation.singularities.index.length, 0);
});

test("the global method's options out of range reject with a PHexError naming them, and the next run works", async () => {
  const cases = [
    [{ anisotropy: 0.5 }, /anisotropy/],
    [{ anisotropy: 9 }, /anisotropy/],
    [{ anisotropy: 'high' }, /anisotropy/],
    [{ alignment: -1 }, /alignment/],
    [{ alignment: 10.5 }, /alignment/],
    [{ alignment: Number.NaN }, /alignment/],
    [{ curvatureSizing: 1.5 }, /curvatureSizing/],
    [{ curvatureSizing: -0.1 }, /curvatureSizing/],
    [{ foldFlips: 'sometimes' }, /foldFlips/],
    [{ dislocations: 'some' }, /dislocations/],
    [{ principalField: 'always' }, /principalField/],
    [{ curvatureFloor: 0 }, /curvatureFloor/],
    [{ curvatureFloor: 1.5 }, /curvatureFloor/],
    [{ curvatureFloor: Number.NaN }, /curvatureFloor/],
    [{ relay: 'twice' }, /relay/],
    [{ fairness: -0.1 }, /fairness/],
    [{ fairness: 2 }, /fairness/],
    [{ cutShare: -0.1 }, /cutShare/],
    [{ cutShare: 2 }, /cutShare/],
  ];
  for (const [options, message] of cases) {
    const error = await phex.run({ surface: 'torus', faces: 300, method: 'global', ...options }).then(
      () => assert.fail(`${JSON.stringify(options)} resolved`),
      (e) => e,
    );
    assert.ok(error instanceof PHexError, `${JSON.stringify(options)}: ${error}`);
    assert.equal(error.code, 'invalid_parameter', JSON.stringify(options));
    assert.match(error.message, message, JSON.stringify(options));
  }
  // The edges of the ranges are accepted, and the module computes again.
  const r = await phex.run({ surface: 'torus', faces: 300, method: 'global', anisotropy: 1, alignment: 0, curvatureSizing: 1 });
  assert.equal(r.method, 'global');
  assert.ok(r.metrics.faceCount > 150, String(r.metrics.faceCount));
});

test("relay reaches the core: a surface the first lay leaves unconverged is laid again and converges", async () => {
  // The Dupin cyclide at 2000 faces, without the solver's fairness (with it, the default, the first lay converges):
  // next to its parabolic circles the first lay follows too little of the Dupin metric. (Along the field held to
  // the principal directions, principalField 'try', the first lay converges: the case lays the smoothest field.)
  const params = { surface: 'cyclide', faces: 2000, method: 'global', fairness: 0, principalField: 'off' };
  const r = await phex.run(params);
  assert.deepEqual([r.relay.tried, r.relay.kept, r.relay.firstReached, r.relay.anisotropy, r.relay.curvatureFloor], [true, true, false, 2.5, 0.05]);
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  assert.ok(r.triangulation.notes.some((n) => /laid again following the Dupin metric/.test(n)), r.triangulation.notes.join('\n'));
  const once = await phex.run({ ...params, relay: 'off' });
  assert.equal(once.relay.tried, false);
  assert.equal(once.solve.converged, false, 'the first lay alone stalls');
  const torus = await globalTorus();
  assert.equal(torus.relay.tried, false, 'a lay that reached a P-Hex mesh with few cuts is not laid again');
});

test("principalField reaches the core: the cyclide's field held to the principal directions has fewer singular points and more hexagons", async () => {
  const params = { surface: 'cyclide', faces: 2000, method: 'global' };
  const held = await phex.run(params);
  const smoothest = await phex.run({ ...params, principalField: 'off' });
  const held6 = held.triangulation.singularities.index.length, smoothest6 = smoothest.triangulation.singularities.index.length;
  assert.ok(held6 <= 0.75 * smoothest6, `${held6} against ${smoothest6} singular points`);
  assert.ok(held.triangulation.notes.some((n) => /held to the principal directions/.test(n)), held.triangulation.notes.join('\n'));
  assert.ok(!smoothest.triangulation.notes.some((n) => /held to the principal directions/.test(n)));
  assert.ok(held.solve.converged && held.metrics.planarityMax <= 1e-9);
  assert.ok(held.metrics.interiorHexagonFraction > smoothest.metrics.interiorHexagonFraction + 0.02,
    `${held.metrics.interiorHexagonFraction} against ${smoothest.metrics.interiorHexagonFraction}`);
});

test('trial lays reach the core: where the lay cuts faces, it is laid again for 3 % fewer and more faces and the best kept', async () => {
  // The Dupin cyclide laid globally at 1000 faces: 10 interior faces cut (20 nodes of four); laid for 970, none (on
  // the lattice where the case was found, its dislocations kept, at the anisotropy then the default).
  const params = { surface: 'cyclide', faces: 1000, method: 'global', dislocations: 'keep', anisotropy: 1.5 };
  const once = await phex.run({ ...params, relay: 'off' });
  const four = (r) => 2 * r.solve.interiorFacesSplit + r.solve.boundaryPanelsSplit;
  assert.ok(four(once) > 0);
  assert.equal(once.relay.trials, 0);
  const r = await phex.run(params);
  assert.ok(r.relay.trials >= 1 && r.relay.trials <= 2, JSON.stringify(r.relay));
  assert.equal(r.relay.trialNodesOfFour, four(once));
  assert.ok([0.97, 1.03].includes(r.relay.trialShare), JSON.stringify(r.relay));
  assert.ok(four(r) < four(once), `${four(r)} against ${four(once)}`);
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9);
  assert.ok(Math.abs(r.metrics.faceCount - 1000) <= 100, String(r.metrics.faceCount));
  assert.ok(r.triangulation.notes.some((n) => /laid again as trials/.test(n)), r.triangulation.notes.join('\n'));
});

test("foldFlips reaches the core: on the torus the notes say how many vertices were merged, and fewer faces are cut", async () => {
  const r = await phex.run({ surface: 'torus', faces: 3000, method: 'global' });
  assert.ok(r.triangulation.notes.some((n) => /[1-9][0-9]* merged with their neighbour along it/.test(n)), r.triangulation.notes.join('\n'));
  assert.ok(r.metrics.planarityMax <= 1e-9, String(r.metrics.planarityMax));
  const plain = await phex.run({ surface: 'torus', faces: 3000, method: 'global', foldFlips: 'off' });
  assert.ok(!plain.triangulation.notes.some((n) => /faces crossing themselves \(each such face would otherwise be cut/.test(n)), 'none when off');
  assert.ok(r.solve.interiorFacesSplit < plain.solve.interiorFacesSplit, `${r.solve.interiorFacesSplit} cut, ${plain.solve.interiorFacesSplit} without flips`);
});

test("dislocations reaches the core: on the torus the note counts the cancelled ones, and 'keep' leaves more irregular vertices", async () => {
  // (Laid once, foldFlips off: the lattice as extracted, before the rounds against folds merge vertices.)
  const options = { surface: 'torus', faces: 3000, method: 'global', relay: 'off', foldFlips: 'off' };
  const r = await phex.run(options);
  assert.ok(r.triangulation.notes.some((n) => /[1-9][0-9]* dislocations of the lattice cancelled before extraction \(0 left\)/.test(n)), r.triangulation.notes.join('\n'));
  const kept = await phex.run({ ...options, dislocations: 'keep' });
  assert.ok(!kept.triangulation.notes.some((n) => /dislocations of the lattice cancelled/.test(n)), 'no note when kept');
  assert.ok(r.metrics.interiorHexagonFraction >= kept.metrics.interiorHexagonFraction + 0.02,
    `${r.metrics.interiorHexagonFraction} cancelled, ${kept.metrics.interiorHexagonFraction} kept`);
});

test("relay reaches the core: an upload whose Method 2 rows leave a spot bare is tiled again by the global method", async () => {
  // The hyperboloid sampled by its parameter lattice (as an upload): one system of rows covers it, but their panels
  // leave a spot over a mean panel edge from any panel at 1000 faces; the global method covers it.
  const sample = await phex.run({ surface: 'hyperboloid', method: 'lattice', faces: 20000, surfaceFit: 'off', clipBoundary: 'off' });
  const mesh = new TextEncoder().encode(meshToOBJ(sample.triangulation));
  const r = await phex.run({ mesh, meshFormat: 'obj', faces: 1000 });
  assert.deepEqual([r.relay.tried, r.relay.globally, r.relay.kept], [true, true, true], JSON.stringify(r.relay));
  assert.ok(r.relay.firstCoverageGap > 1, String(r.relay.firstCoverageGap));
  assert.equal(r.method, 'global');
  assert.ok(r.coverageGap <= 1, String(r.coverageGap));
  assert.ok(r.solve.converged && r.metrics.planarityMax <= 1e-9);
  assert.ok(r.triangulation.notes.some((n) => /laid again by the global method/.test(n)), r.triangulation.notes.join('\n'));
  const rows = await phex.run({ mesh, meshFormat: 'obj', faces: 1000, relay: 'off' });
  assert.equal(rows.method, 'prespecified');
  assert.equal(rows.relay.tried, false);
  assert.ok(rows.coverageGap > 1, String(rows.coverageGap));
});
