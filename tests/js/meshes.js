// phex — meshes generated for the tests (JS API and browser), as file bytes, and checks of the P-Hex meshes
// phex returns for them.
import assert from 'node:assert/strict';

/**
 * A closed genus-0 blob as OFF bytes: an icosahedron subdivided `levels` times, pushed onto an ellipsoid with a
 * dent (not convex, so it is no sphere in disguise), moved by `shift`.
 */
export function blobOFF(levels = 3, shift = [0, 0, 0]) {
  const t = (1 + Math.sqrt(5)) / 2;
  let points = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]];
  let triangles = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
    [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]];
  const unit = (p) => p.map((x) => x / Math.hypot(...p));
  points = points.map(unit);
  for (let level = 0; level < levels; level++) {
    const middle = new Map();
    const mid = (a, b) => {
      const key = Math.min(a, b) * 100000 + Math.max(a, b);
      if (!middle.has(key)) middle.set(key, points.push(unit(points[a].map((x, k) => x + points[b][k]))) - 1);
      return middle.get(key);
    };
    triangles = triangles.flatMap(([a, b, c]) => {
      const [ab, bc, ca] = [mid(a, b), mid(b, c), mid(c, a)];
      return [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]];
    });
  }
  const placed = points.map(([x, y, z]) => {
    const r = 1 - 0.25 * Math.exp(-((x - 0.8) ** 2 + y ** 2) * 4);  // the dent
    return [1.5 * r * x + shift[0], r * y + shift[1], 0.8 * r * z + shift[2]];
  });
  const lines = ['OFF', `${placed.length} ${triangles.length} 0`, ...placed.map((p) => p.join(' ')), ...triangles.map((f) => `3 ${f.join(' ')}`)];
  return new TextEncoder().encode(`${lines.join('\n')}\n`);
}

/** Faces at each node of a polygon mesh, and the number of edges of one face (the boundary's). */
function nodeFaces({ positions, faceOffsets, faceIndices }) {
  const faces = new Uint32Array(positions.length / 3);
  const edgeUses = new Map();
  for (let f = 0; f + 1 < faceOffsets.length; f++) {
    const first = faceOffsets[f];
    const n = faceOffsets[f + 1] - first;
    for (let i = 0; i < n; i++) {
      const a = faceIndices[first + i];
      const b = faceIndices[first + ((i + 1) % n)];
      faces[a]++;
      const key = Math.min(a, b) * 0x100000000 + Math.max(a, b);
      edgeUses.set(key, (edgeUses.get(key) ?? 0) + 1);
    }
  }
  return { faces, boundaryEdges: [...edgeUses.values()].filter((u) => u === 1).length };
}

/** Σ (6 − corners) over the faces of a polygon mesh: 12 (1 − g) for a closed one whose nodes all join three faces (Euler). */
export function hexagonDefect({ faceOffsets }) {
  let sum = 0;
  for (let f = 0; f + 1 < faceOffsets.length; f++) sum += 6 - (faceOffsets[f + 1] - faceOffsets[f]);
  return sum;
}

/** The singular points' arrays agree with each other: three coordinates and one non-zero integer index per point. */
export function assertSingularities(singularities) {
  const { positions, index } = singularities;
  assert.ok(positions instanceof Float64Array, 'positions is a Float64Array');
  assert.ok(index instanceof Int32Array, 'index is an Int32Array');
  assert.equal(positions.length, 3 * index.length);
  assert.ok(positions.every(Number.isFinite));
  assert.ok(index.every((i) => i !== 0), `indices ${[...index]}`);
  return index.reduce((a, b) => a + b, 0);
}

/** Σ (6 − valence) over the vertices of a triangle mesh ({positions, triangles}), and its edges of one triangle. */
function valenceDefect({ positions, triangles }) {
  const valence = new Uint32Array(positions.length / 3);
  for (const v of triangles) valence[v]++;
  const polygons = { positions, faceOffsets: Uint32Array.from({ length: triangles.length / 3 + 1 }, (_, f) => 3 * f), faceIndices: triangles };
  return { defect: valence.reduce((sum, n) => sum + 6 - n, 0), boundaryEdges: nodeFaces(polygons).boundaryEdges };
}

// The dual of a closed triangle mesh of genus g is closed, every node joins three faces, and Σ (6 − corners) over
// its faces is 12 (1 − g), as Σ (6 − valence) is over the triangulation's vertices. Where the solve cuts a face in
// two to reach planarity (solve.interiorFacesSplit), the cut puts a fourth face at its two ends and adds 4 to that
// sum. Issue 31's goal is no cut at all (assertNoCut).
/** Asserts the above of a run's result `r` on a closed surface of genus `genus`. */
export function assertClosedDual(r, genus) {
  const euler = 12 * (1 - genus);
  const laid = valenceDefect(r.triangulation);
  assert.equal(laid.boundaryEdges, 0, 'a closed surface gives a closed triangulation');
  assert.equal(laid.defect, euler, 'Σ (6 − valence) over the triangulation');
  const cuts = r.solve.interiorFacesSplit;
  const { faces, boundaryEdges } = nodeFaces(r.hex);
  assert.equal(boundaryEdges, 0, 'a closed surface gives a closed P-Hex mesh');
  assert.ok(faces.every((n) => n >= 3));
  assert.equal(faces.reduce((sum, n) => sum + n - 3, 0), 2 * cuts, `nodes of more than three faces, ${cuts} faces cut`);
  assert.equal(hexagonDefect(r.hex), euler + 4 * cuts, 'Σ (6 − corners) over the P-Hex mesh');
}

/** Issue 31's goal for the global method: no face cut, so every node of the P-Hex mesh joins three faces. */
export function assertNoCut(r) {
  const summary = JSON.stringify({ bySize: r.metrics.facesBySize, faceCut: r.solve.interiorFacesSplit, planarity: r.metrics.planarityMax });
  assert.equal(r.solve.interiorFacesSplit, 0, summary);
  assert.deepEqual(r.metrics.vertexValence, { 3: r.metrics.vertexCount }, summary);
}
