// The command-line tool, run as a user would: outputs, reports and errors with exit codes.
import { after, test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const PHEX = new URL('../../build/native/bin/phex', import.meta.url).pathname;
const dir = mkdtempSync(join(tmpdir(), 'phex-cli-'));
after(() => rmSync(dir, { recursive: true, force: true }));

function phex(...args) {
  return phexWith({}, ...args);
}

function phexWith(env, ...args) {
  const r = spawnSync(PHEX, args, { encoding: 'utf8', env: { ...process.env, ...env } });
  return { code: r.status, out: r.stdout, err: r.stderr };
}

test('--help documents the commands and options', () => {
  const r = phex('--help');
  assert.equal(r.code, 0);
  for (const word of ['run', 'curvature', 'surfaces', '--faces', '--cell', '--report', '--solver', '--duality', '--panels']) {
    assert.ok(r.out.includes(word), `help mentions ${word}`);
  }
});

test('run writes the P-Hex mesh as OBJ and a JSON report', () => {
  const obj = join(dir, 'hex.obj');
  const report = join(dir, 'report.json');
  const r = phex('run', '--surface', 'torus', '--faces', '2000', '--out', obj, '--report', report, '--quiet');
  assert.equal(r.code, 0, r.err);
  const rep = JSON.parse(readFileSync(report, 'utf8'));
  assert.ok(rep.planarity.max <= 1e-9);
  assert.equal(rep.invalidFaces, 0);
  assert.ok(rep.mesh.facesBySize['6'] > 1500);
  assert.ok(rep.solver.iterations >= 1);
  for (const stage of ['triangulate', 'dualize', 'planarize', 'measure', 'total']) assert.ok(rep.milliseconds[stage] >= 0);
  const faces = readFileSync(obj, 'utf8').split('\n').filter((l) => l.startsWith('f ')).length;
  assert.equal(faces, rep.mesh.faces);
});

test('a run that stops short of the tolerance still writes its mesh, exits 2 and says why on stderr', () => {
  const obj = join(dir, 'across.obj');
  const report = join(dir, 'across.json');
  // Hexagons across a cylinder's rulings (the field turned 45 degrees) cannot all be planar: no solve converges.
  const r = phex('run', '--surface', 'cylinder', '--method', 'prespecified', '--field', 'angle:45', '--faces', '2000', '--out', obj, '--report', report, '--quiet');
  assert.equal(r.code, 2, r.err);
  assert.match(r.err, /not converged: planarity max [0-9.e+-]+ is above the tolerance 1e-0?9/);
  assert.ok(existsSync(obj));
  const rep = JSON.parse(readFileSync(report, 'utf8'));
  assert.equal(rep.solver.converged, false);
  assert.equal(rep.solver.method, 'local');
  // The report names the solver asked for.
  const reference = phex('run', '--surface', 'sphere', '--faces', '200', '--solver', 'volumes', '--report', report, '--quiet');
  assert.equal(reference.code, 0, reference.err);
  assert.equal(JSON.parse(readFileSync(report, 'utf8')).solver.method, 'volumes');
});

test('a PHEX_THREADS that is not a count is an error naming it; --threads overrides it', () => {
  for (const value of ['abc', '-1', '2x', '99999999999999999999']) {
    const r = phexWith({ PHEX_THREADS: value }, 'run', '--surface', 'torus', '--faces', '300', '--out', join(dir, 'env.obj'), '--quiet');
    assert.equal(r.code, 1, `PHEX_THREADS=${value} exits 1`);
    assert.match(r.err, /the PHEX_THREADS environment variable is '.*': it must be a whole number/, value);
    assert.ok(!existsSync(join(dir, 'env.obj')), 'no mesh written');
  }
  const ok = phexWith({ PHEX_THREADS: 'abc' }, 'run', '--surface', 'torus', '--faces', '300', '--threads', '1', '--out', join(dir, 'env.obj'), '--quiet');
  assert.equal(ok.code, 0, ok.err);
  assert.equal(phexWith({ PHEX_THREADS: '0' }, 'run', '--surface', 'torus', '--faces', '300', '--out', join(dir, 'env0.obj'), '--quiet').code, 0);
});

test('--threads changes the time, not the mesh', () => {
  const outputs = ['1', '2'].map((n) => {
    const obj = join(dir, `threads-${n}.obj`), report = join(dir, `threads-${n}.json`);
    const r = phex('run', '--surface', 'wave-roof', '--faces', '1500', '--threads', n, '--out', obj, '--report', report, '--quiet');
    assert.equal(r.code, 0, r.err);
    assert.equal(JSON.parse(readFileSync(report, 'utf8')).threads, Number(n));
    return readFileSync(obj, 'utf8');
  });
  assert.equal(outputs[0], outputs[1]);
});

test('--cell is an alternative to --faces', () => {
  const report = join(dir, 'cell.json');
  assert.equal(phex('run', '--surface', 'sphere', '--cell', '0.2', '--report', report, '--quiet').code, 0);
  assert.ok(JSON.parse(readFileSync(report, 'utf8')).mesh.faces > 50);
});

test('bad input gives a message and exit code 1', () => {
  const cases = [
    [['run', '--surface', 'teapot'], /unknown surface 'teapot'/],
    [['run', '--faces', '0'], /faces must be between/],
    [['run', '--faces', '5000000000'], /--faces expects an integer|faces must be between/],
    [['run', '--faces', 'many'], /--faces expects a number/],
    [['run', '--tolerance', 'nan'], /--tolerance expects a number/],
    [['run', '--out', join(dir, 'no/such/dir/hex.obj')], /cannot open .*no\/such\/dir/],
    [['run', '--solver', 'magic'], /solver must be/],
    [['run', '--folds', 'maybe'], /--folds must be prevent or allow/],
    [['run', '--surface-fit', 'maybe'], /--surface-fit must be on or off/],
    [['run', '--split-boundary', 'maybe'], /--split-boundary must be on or off/],
    [['run', '--clip-boundary', 'sometimes'], /--clip-boundary must be on or off/],
    [['run', '--fold-flips', 'sometimes'], /--fold-flips must be on or off/],
    [['run', '--dislocations', 'some'], /--dislocations must be cancel or keep/],
    [['run', '--principal-field', 'always'], /--principal-field must be try or off/],
    [['run', '--relay', 'twice'], /--relay must be on or off/],
    [['run', '--fairness', '2'], /fairness must be in \[0, 1\]/],
    [['run', '--cut-share', '1.5'], /cutShare must be in \[0, 1\]/],
    [['run', '--curvature-floor', '0'], /curvatureFloor must be in \[0\.01, 1\]/],
    [['run', '--start', '1,2'], /--start expects X,Y,Z/],
    [['run', '--direction', '0,0,0'], /direction must be a non-zero vector/],
    [['run', '--param', 'R'], /NAME=VALUE/],
    [['frobnicate'], /unknown command/],
    [['run', '--method', 'random'], /method must be/],
    [['run', '--field', 'sideways'], /sideways/],
    [['run', '--field', 'section:200'], /section:200.*outside \[-180, 180\]/],
    [['run', '--solver', 'gauss-newton'], /solver must be 'local', 'planes' or 'volumes'/],
    [['run', '--lower-bound', '5'], /lowerBound must be in \[0, 2\]/],
    [['run', '--format', 'dxf', '--out', join(dir, 'x.dxf')], /--format must be obj, ply or json/],
    [['run', '--mesh', join(dir, 'missing.stl')], /cannot open .*missing\.stl/],
    [['run', '--method', 'subdivision', '--surface', 'torus'], /control mesh/],
    [['triangulate', '--surface', 'teapot'], /unknown surface 'teapot'/],
    [['curvature', '--mesh', join(dir, 'missing.obj'), '--out', join(dir, 'c.csv')], /missing\.obj/],
    [['run', '--panels', join(dir, 'p.dxf')], /--panels writes \.svg or \.csv/],
    [['run', '--panels', join(dir, 'p.svg'), '--panel-gap', '-1'], /--panel-gap must be 0 or more/],
    [['run', '--panels', join(dir, 'p.svg'), '--panel-width', '-2'], /--panel-width must be 0 or more/],
    [['run', '--panels', join(dir, 'p.svg'), '--panel-gap', 'wide'], /--panel-gap expects a number/],
    [['run', '--panels', join(dir, 'p.svg'), '--panel-unit', 'ft'], /--panel-unit must be mm, cm, m or in/],
    [['triangulate', '--panels', join(dir, 'p.svg')], /--panels needs phex run/],
    [['triangulate', '--beams', join(dir, 'b.csv')], /--beams needs phex run/],
    [['run', '--offset', '0', '--offset-mesh', join(dir, 'o.obj')], /offset must be a finite number other than 0 \(got 0\)/],
    [['run', '--offset', '0.1'], /--offset needs --offset-mesh/],
    [['run', '--offset-mesh', join(dir, 'o.obj')], /--offset-mesh needs --offset D/],
    [['run', '--offset', '0.1', '--offset-mesh', join(dir, 'o.stl')], /--offset-mesh writes \.obj, \.ply, \.glb or \.gltf/],
    [['run', '--beam-height', '-0.1', '--structure', join(dir, 's.glb')], /beamHeight must be a positive number \(got -0\.1\)/],
    [['run', '--beam-width', '0', '--structure', join(dir, 's.glb')], /beamWidth must be a positive number/],
    [['run', '--panel-thickness', 'thin', '--structure', join(dir, 's.glb')], /--panel-thickness expects a number/],
    [['run', '--structure', join(dir, 's.stl')], /--structure writes \.glb, \.gltf or \.obj/],
    [['triangulate', '--nodes', join(dir, 'n.csv')], /structure options .* need phex run/],
    [['run', '--surface', 'hyperboloid', '--faces', '300', '--beam-height', '50', '--structure', join(dir, 's.glb')], /beamHeight = 50 \(face distance -50\) is more than the offset can take: the edge between nodes \d+ and \d+ of panel P\d+( \(and P\d+\))? vanishes at face distance -[0-9.]+; face distances from -[0-9.]+ to [0-9.]+ can be taken/],
    [['run', '--threads', '-1'], /--threads must be 0 \(the default\) or more/],
    [['run', '--threads', 'all'], /--threads expects a number/],
  ];
  for (const [args, pattern] of cases) {
    const r = phex(...args);
    assert.equal(r.code, 1, `${args.join(' ')} exits 1`);
    assert.match(r.err, pattern, args.join(' '));
  }
});

test('run --panels writes the faces laid flat: an SVG cut sheet and a CSV schedule, one per face', () => {
  const report = join(dir, 'panels.json');
  const svg = join(dir, 'panels.svg');
  const csv = join(dir, 'panels.csv');
  assert.equal(phex('run', '--surface', 'hyperboloid', '--faces', '600', '--panels', svg, '--panel-unit', 'm', '--report', report, '--quiet').code, 0);
  assert.equal(phex('run', '--surface', 'hyperboloid', '--faces', '600', '--panels', csv, '--quiet').code, 0);
  const { mesh: { faces }, boundaryFaces } = JSON.parse(readFileSync(report, 'utf8'));
  const sheet = readFileSync(svg, 'utf8');
  assert.equal((sheet.match(/<polygon id="P\d+"/g) ?? []).length, faces);
  assert.match(sheet, /<svg [^>]*width="[0-9.e+-]+mm"/);
  const rows = readFileSync(csv, 'utf8').trimEnd().split('\n');
  assert.equal(rows.length, faces + 1);
  // K < 0 throughout: every hexagon is non-convex (§3), a corner angle over 180 degrees; but for boundary panels,
  // whose corners on the boundary follow the curve (clipped to it), six of them or not.
  const hexagons = rows.slice(1).map((r) => r.split(',')).filter((c) => c[1] === '6');
  assert.ok(hexagons.length > 0.8 * faces);
  const convex = hexagons.filter((c) => !c[12].split(';').some((a) => Number(a) > 180)).length;
  assert.ok(convex <= boundaryFaces, `${convex} convex hexagons, ${boundaryFaces} boundary panels`);
  // The beam schedule: every edge once; at the boundary one panel, inside two.
  const beams = join(dir, 'beams.csv');
  assert.equal(phex('run', '--surface', 'hyperboloid', '--faces', '600', '--beams', beams, '--quiet').code, 0);
  const edges = readFileSync(beams, 'utf8').trimEnd().split('\n').slice(1).map((r) => r.split(','));
  const corners = rows.slice(1).reduce((n, r) => n + Number(r.split(',')[1]), 0);
  const boundary = edges.filter((c) => c[5] === '').length;
  assert.ok(boundary > 0);
  assert.equal(2 * edges.length - boundary, corners, 'each face edge counted once per side');
});

test('run --offset, --beam-height, --structure and --nodes write the structure on the panels', async () => {
  const hex = join(dir, 's-hex.obj'), offset = join(dir, 's-offset.obj'), glb = join(dir, 's.glb'), nodes = join(dir, 's-nodes.csv');
  const beams = join(dir, 's-beams.csv'), report = join(dir, 's.json');
  const r = phex('run', '--surface', 'hyperboloid', '--faces', '600', '--out', hex, '--offset', '-0.05', '--offset-mesh', offset,
    '--beam-height', '0.04', '--beam-width', '0.01', '--panel-thickness', '0.005', '--structure', glb, '--nodes', nodes,
    '--beams', beams, '--report', report);
  assert.equal(r.code, 0, r.err);
  assert.match(r.err, /structure: boundary: \d+ of \d+ boundary beams planar/);
  // The offset pairs up with the P-Hex mesh line by line: as many vertices, the same faces.
  const [a, b] = [hex, offset].map((f) => readFileSync(f, 'utf8').trimEnd().split('\n').filter((l) => !l.startsWith('#')));
  assert.equal(a.length, b.length);
  assert.deepEqual(a.filter((l) => l.startsWith('f ')), b.filter((l) => l.startsWith('f ')));
  const moved = a.filter((l, i) => l.startsWith('v ') && l !== b[i]).length;
  assert.equal(moved, a.filter((l) => l.startsWith('v ')).length, 'every node moves');
  const rep = JSON.parse(readFileSync(report, 'utf8'));
  const s = rep.structure;
  assert.equal(s.offset, -0.05);
  assert.equal(s.beamHeight, 0.04);
  assert.ok(s.nodes.cone > 0 && s.nodes.boundary > 0);
  assert.equal(s.nodes['best-fit'] + s.nodes.folded, 0);
  assert.equal(s.boundaryBeamsPlanar, s.boundaryBeams, 'the hyperboloid rims: every boundary beam planar');
  assert.ok(s.beamPlanarityMax <= 1e-9);
  assert.ok(s.offsetRange[0] < -0.05 && s.offsetRange[1] > 0.005, JSON.stringify(s.offsetRange));
  // The node schedule: one row per node, three panels and three equal angles at a cone node.
  const rows = readFileSync(nodes, 'utf8').trimEnd().split('\n').map((l) => l.split(','));
  assert.equal(rows[0].join(), 'node,kind,faces,x,y,z,axis_x,axis_y,axis_z,scale,panels,axis_face_angles_deg,normal_deviation_deg,residual');
  assert.equal(rows.length - 1, rep.mesh.vertices);
  for (const row of rows.slice(1).filter((c) => c[1] === 'cone')) {
    assert.equal(row[10].split(';').length, 3);
    const angles = row[11].split(';').map(Number);
    assert.ok(Math.max(...angles) - Math.min(...angles) < 1e-6, row.join());
  }
  // The beam schedule extended with heights, plane, planarity, twist and the quad's corners.
  const beamRows = readFileSync(beams, 'utf8').trimEnd().split('\n').map((l) => l.split(','));
  assert.match(beamRows[0].join(), /^beam,node_a,node_b,length,.*,height_a,height_b,plane_nx,plane_ny,plane_nz,plane_offset,planarity,twist_deg,q1x,.*,q4z$/);
  assert.equal(beamRows.length - 1, s.beams);
  for (const row of beamRows.slice(1)) assert.ok(Number(row[19]) <= 1e-9 && Number(row[13]) >= 0.04, row.join());
  // The solid model as glTF: panels, beams (12 triangles each) and axes, the counts in the scene's extras.
  const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
  const data = readFileSync(glb);
  const gltf = await new GLTFLoader().parseAsync(data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength), '');
  const parts = {};
  gltf.scene.traverse((o) => { if (o.geometry) parts[o.name] = o; });
  assert.equal(gltf.scene.userData.beams, s.beams);
  assert.equal(parts.beams.geometry.index.count, 3 * 12 * s.beams);
  assert.equal(gltf.scene.userData.panels, rep.mesh.faces);
  assert.ok(parts.axes.isLineSegments);
  // And as OBJ: an object per panel and per beam.
  const obj = join(dir, 's.obj');
  assert.equal(phex('run', '--surface', 'hyperboloid', '--faces', '600', '--structure', obj, '--quiet').code, 0);
  const objects = readFileSync(obj, 'utf8').split('\n').filter((l) => l.startsWith('o '));
  assert.equal(objects.filter((l) => l.startsWith('o B')).length, s.beams);
  assert.equal(objects.filter((l) => l.startsWith('o P')).length, rep.mesh.faces);
});

test('curvature of an uploaded mesh keeps the vertex order; bad files are named', () => {
  // A small height field z = (x^2 - y^2) / 2 as OBJ.
  const n = 12;
  let obj = '';
  for (let j = 0; j <= n; j++) for (let i = 0; i <= n; i++) {
    const x = (i / n - 0.5) * 0.6, y = (j / n - 0.5) * 0.6;
    obj += `v ${x} ${y} ${(x * x - y * y) / 2}\n`;
  }
  for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) {
    const a = j * (n + 1) + i + 1;
    obj += `f ${a} ${a + 1} ${a + n + 2}\nf ${a} ${a + n + 2} ${a + n + 1}\n`;
  }
  const input = join(dir, 'saddle.obj'), out = join(dir, 'saddle.csv');
  writeFileSync(input, obj);
  const r = phex('curvature', '--mesh', input, '--out', out);
  assert.equal(r.code, 0, r.err);
  const rows = readFileSync(out, 'utf8').trim().split('\n');
  assert.equal(rows[0], 'x,y,z,k1,k2,d1x,d1y,d1z,d2x,d2y,d2z');
  assert.equal(rows.length, (n + 1) * (n + 1) + 1);
  const centre = rows[1 + (n / 2) * (n + 1) + n / 2].split(',').map(Number);
  assert.ok(Math.abs(centre[0]) < 1e-12 && Math.abs(centre[1]) < 1e-12);
  assert.ok(Math.abs(centre[3] - 1) < 0.05 && Math.abs(centre[4] + 1) < 0.05, `k1, k2 at the saddle: ${centre[3]}, ${centre[4]}`);

  const bad = join(dir, 'bad.obj');
  writeFileSync(bad, 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n');
  const e = phex('curvature', '--mesh', bad, '--out', join(dir, 'bad.csv'));
  assert.equal(e.code, 1);
  assert.match(e.err, /bad\.obj.*line 4/);
  assert.ok(!existsSync(join(dir, 'bad.csv')) || readFileSync(join(dir, 'bad.csv'), 'utf8') === '');
});

test("fuzzing's files are refused within a second (exit 1, naming the problem); a 40,000-corner cap is read", () => {
  const regressions = JSON.parse(readFileSync(new URL('../fuzz/regressions.json', import.meta.url), 'utf8'));
  for (const [file, message] of Object.entries(regressions).filter(([f]) => f !== '//')) {
    const path = new URL(`../fuzz/regressions/${file}`, import.meta.url).pathname;
    for (const command of ['run', 'curvature']) {
      const started = performance.now();
      const r = phex(command, '--mesh', path, '--out', join(dir, 'refused.out'));
      const ms = performance.now() - started;
      assert.equal(r.code, 1, `${command} ${file}: ${r.err}`);
      assert.ok(r.err.includes(file) && r.err.includes(message), r.err);
      assert.ok(ms < 1000, `${command} ${file}: ${ms} ms`);
    }
  }
  // One face of 40,000 corners (a flat cap as CAD tools write it): ear-clipped in near-linear time.
  const n = 40000;
  let cap = '';
  for (let i = 0; i < n; i++) cap += `v ${Math.cos((2 * Math.PI * i) / n).toFixed(6)} ${Math.sin((2 * Math.PI * i) / n).toFixed(6)} 0\n`;
  cap += `f ${Array.from({ length: n }, (_, i) => i + 1).join(' ')}\n`;
  const input = join(dir, 'cap.obj'), out = join(dir, 'cap.csv');
  writeFileSync(input, cap);
  const started = performance.now();
  const r = phex('curvature', '--mesh', input, '--out', out);
  assert.equal(r.code, 0, r.err);
  assert.equal(readFileSync(out, 'utf8').trim().split('\n').length, n + 1);
  assert.ok(performance.now() - started < 10000, `${performance.now() - started} ms`);  // was over a minute
});

test('curvature of an analytic surface is exact', () => {
  const out = join(dir, 'sphere.csv');
  assert.equal(phex('curvature', '--surface', 'sphere', '--param', 'R=2', '--faces', '200', '--out', out).code, 0);
  const rows = readFileSync(out, 'utf8').trim().split('\n').slice(1).map((l) => l.split(',').map(Number));
  for (const r of rows) assert.ok(Math.abs(r[3] - 0.5) < 1e-12 && Math.abs(r[4] - 0.5) < 1e-12);
});

test("the report lists the global field's singular points, their indices adding up to the surface's Euler characteristic", () => {
  // Poincare-Hopf for a 6-fold field: the indices (sixths of a turn) add up to 6 chi.
  const cases = [
    [['--mesh', new URL('../../web/models/phcpf_3holes_r.off', import.meta.url).pathname], 6 * (2 - 2 * 3)],
    [['--surface', 'torus', '--method', 'global'], 0],
  ];
  for (const [args, sum] of cases) {
    const report = join(dir, 'singular.json');
    const r = phex('triangulate', ...args, '--faces', '400', '--quiet', '--report', report);
    assert.equal(r.code, 0, r.err);
    const { singularities, methodUsed } = JSON.parse(readFileSync(report, 'utf8'));
    assert.equal(methodUsed, 'global');
    assert.equal(singularities.reduce((s, x) => s + x.index, 0), sum, JSON.stringify(singularities));
    for (const s of singularities) {
      assert.ok([-1, 1].includes(s.index) || Math.abs(s.index) <= 3, `index ${s.index}`);
      assert.ok(s.position.length === 3 && s.position.every(Number.isFinite));
    }
  }
  // The methods along rows report none.
  const report = join(dir, 'rows.json');
  assert.equal(phex('triangulate', '--surface', 'torus', '--method', 'lattice', '--faces', '300', '--quiet', '--report', report).code, 0);
  assert.deepEqual(JSON.parse(readFileSync(report, 'utf8')).singularities, []);
});
