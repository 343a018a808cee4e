// phex — browser tests of the web app (build/web): headless Chromium through playwright-core.
// Needs `npx vite build --config web/vite.config.js` (or `npm run build:web`) first, and /usr/bin/chromium.
import assert from 'node:assert/strict';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from '../../scripts/serve.js';
import { blobOFF } from '../js/meshes.js';

const repo = fileURLToPath(new URL('../..', import.meta.url));
const webDir = join(repo, 'build/web');
const artifacts = join(repo, 'build/test-artifacts');
const CHROMIUM = process.env.PHEX_CHROMIUM ?? '/usr/bin/chromium';
const BACKGROUND = [0xee, 0xf1, 0xf5]; // web/main.js BACKGROUND
const RUN_TIMEOUT_MS = 120_000; // wasm under a 2-core CI machine, without GPU

let server;
let url;
let context;
let profile;
let page;
const pageErrors = [];

before(async () => {
  assert.ok(existsSync(join(webDir, 'index.html')), 'build/web is missing: run `npm run build:web` first');
  ({ server, url } = await serve(webDir, 0));
  // A fresh profile each run, so no cache or state of an earlier run leaks in.
  profile = mkdtempSync(join(tmpdir(), 'phex-chromium-'));
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--no-first-run', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    ],
    viewport: { width: 1200, height: 800 },
    acceptDownloads: true,
  });
  page = context.pages()[0] ?? (await context.newPage());
  page.on('pageerror', (error) => pageErrors.push(error.message));
  await page.goto(url);
});

after(async () => {
  await context?.close();
  server?.close();
  if (profile) rmSync(profile, { recursive: true, force: true });
});

/**
 * Counts pixels of a PNG screenshot, decoded in the page, within `tolerance` of the colour `rgb` (the sum of the
 * channels' differences), of `total`.
 */
async function pixelsNear(png, rgb, tolerance, on = page) {
  return on.evaluate(
    async ({ data, rgb, tolerance }) => {
      const bitmap = await createImageBitmap(new Blob([Uint8Array.from(atob(data), (c) => c.charCodeAt(0))]));
      const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
      const ctx = canvas.getContext('2d');
      ctx.drawImage(bitmap, 0, 0);
      const { data: pixels } = ctx.getImageData(0, 0, bitmap.width, bitmap.height);
      let near = 0;
      for (let i = 0; i < pixels.length; i += 4) {
        if (Math.abs(pixels[i] - rgb[0]) + Math.abs(pixels[i + 1] - rgb[1]) + Math.abs(pixels[i + 2] - rgb[2]) <= tolerance) near++;
      }
      return { near, total: pixels.length / 4 };
    },
    { data: png.toString('base64'), rgb, tolerance },
  );
}

/** Counts pixels of a PNG screenshot that differ clearly from the background colour. */
async function nonBackgroundPixels(png, on = page, background = BACKGROUND) {
  const { near, total } = await pixelsNear(png, background, 24, on);
  return { count: total - near, total };
}

test('the default torus is computed and drawn on load', async () => {
  await page.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
  const planarity = Number(await page.textContent('#planarity-max'));
  assert.ok(Number.isFinite(planarity) && planarity <= 1e-9, `planarity max ${planarity}`);
  assert.ok(Number(await page.textContent('#face-count')) > 1000);
  assert.equal(await page.textContent('#invalid-faces'), '0');
  assert.equal(await page.inputValue('#surface'), 'torus');
  // The summaries of the metrics: hexagons, faces at nodes (3 at every node of the closed torus), the
  // diagonal planarity measure and the spreads of edge length and face area.
  assert.ok(Number.parseFloat(await page.textContent('#hexagon-share')) >= 90, await page.textContent('#hexagon-share'));
  assert.match(await page.textContent('#node-faces'), /^3: \d+$/);
  assert.match(await page.textContent('#planarity-diagonals'), /^\S+ % max$/);
  for (const id of ['#edge-length', '#face-area']) {
    assert.match(await page.textContent(id), /^\S+ – \S+ \(×\d+\.\d\)$/, id);
    assert.match(await page.getAttribute(id, 'title'), /^mean \S+$/, id);
  }

  const png = await page.locator('#viewport').screenshot();
  mkdirSync(artifacts, { recursive: true });
  await page.screenshot({ path: join(artifacts, 'app.png') });
  const { count, total } = await nonBackgroundPixels(png);
  assert.ok(count > total * 0.05, `only ${count} of ${total} viewport pixels show the mesh`);
  assert.deepEqual(pageErrors, []);
});

test('a bad parameter shows an error, and the next valid edit works again', async () => {
  await page.fill('#faces', '0');
  await page.waitForSelector('body[data-state=error]', { timeout: RUN_TIMEOUT_MS });
  assert.ok(await page.isVisible('#error'));
  assert.match(await page.textContent('#error'), /faces/);

  await page.fill('#faces', '300');
  await page.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
  assert.ok(!(await page.isVisible('#error')));
  const faces = Number(await page.textContent('#face-count'));
  assert.ok(faces > 150 && faces < 600, `face count ${faces} for 300 wanted`);
  assert.ok(Number(await page.textContent('#planarity-max')) <= 1e-9);
  assert.deepEqual(pageErrors, []);
});

test('cancel stops a run and the page stays usable', async () => {
  // Large enough to still be running when Cancel is clicked.
  await page.fill('#faces', '300000');
  await page.waitForSelector('body[data-state=running]');
  await page.click('#cancel');
  await page.waitForSelector('body[data-state=ready]', { timeout: 10_000 });
  assert.equal(await page.textContent('#stage'), 'cancelled');

  await page.fill('#faces', '500');
  await page.waitForFunction(() => document.body.dataset.state === 'ready' && document.getElementById('stage').textContent.startsWith('done'), null, { timeout: RUN_TIMEOUT_MS });
  assert.deepEqual(pageErrors, []);
});

test('export OBJ downloads the mesh', async () => {
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  const text = readFileSync(await download.path(), 'utf8');
  const faces = text.split('\n').filter((l) => l.startsWith('f ')).length;
  assert.equal(faces, Number(await page.textContent('#face-count')));
});


/** Counts pixels of a PNG screenshot near the colour `rgb` (see pixelsNear). */
async function pixelsOf(png, rgb, tolerance = 60) {
  return (await pixelsNear(png, rgb, tolerance)).near;
}
// The singular points' markers (web/viewer.js PENTAGON_COLOR, HEPTAGON_COLOR), drawn unlit.
const PENTAGON_RGB = [0xe0, 0x20, 0x1c];
const HEPTAGON_RGB = [0x1f, 0x4f, 0xe0];

/** Runs the action and waits until the app has finished the run it started (or the runs it queued). */
async function afterRun(action, on = page) {
  const runs = Number(await on.getAttribute('body', 'data-runs'));
  await action();
  await on.waitForFunction((n) => Number(document.body.dataset.runs) > n && document.body.dataset.state !== 'running', runs, { timeout: RUN_TIMEOUT_MS });
}

async function downloadOf(buttonId) {
  const [download] = await Promise.all([page.waitForEvent('download'), page.click(buttonId)]);
  return { name: download.suggestedFilename(), data: readFileSync(await download.path()) };
}

test('export PLY, JSON, glTF, the triangulation and a PNG', async () => {
  const faceCount = Number(await page.textContent('#face-count'));
  const ply = (await downloadOf('#export-ply')).data.toString('utf8');
  assert.match(ply, /^ply\n/);
  const header = ply.slice(0, ply.indexOf('end_header'));
  assert.equal(Number(header.match(/element face (\d+)/)[1]), faceCount);
  const vertices = Number(header.match(/element vertex (\d+)/)[1]);
  const body = ply.slice(ply.indexOf('end_header') + 11).trimEnd().split('\n');
  assert.equal(body.length, vertices + faceCount, 'one line per vertex and per face');
  assert.equal(body.slice(vertices).filter((l) => Number(l.split(' ')[0]) >= 3).length, faceCount);

  const json = JSON.parse((await downloadOf('#export-json')).data.toString('utf8'));
  assert.equal(json.metrics.faceCount, faceCount);
  assert.equal(json.mesh.faceOffsets.length, faceCount + 1);
  assert.equal(json.metrics.planarity.length, faceCount);

  const glb = await downloadOf('#export-gltf');
  assert.match(glb.name, /\.glb$/);
  assert.equal(glb.data.subarray(0, 4).toString('latin1'), 'glTF');

  const tri = (await downloadOf('#export-tri')).data.toString('utf8');
  assert.ok(tri.split('\n').filter((l) => l.startsWith('f ')).length > faceCount, 'about two triangles per hexagon');

  const png = await downloadOf('#export-png');
  assert.deepEqual([...png.data.subarray(1, 4)], [...Buffer.from('PNG')]);

  // The panels laid flat: one labelled outline per face, and the schedule with one row per face.
  const svg = await downloadOf('#export-panels');
  assert.match(svg.name, /-panels\.svg$/);
  assert.equal((svg.data.toString('utf8').match(/<polygon id="P\d+"/g) ?? []).length, faceCount);
  const csv = (await downloadOf('#export-schedule')).data.toString('utf8').trimEnd().split('\n');
  assert.match(csv[0], /^panel,corners,area/);
  assert.equal(csv.length, faceCount + 1);
  const beams = (await downloadOf('#export-beams')).data.toString('utf8').trimEnd().split('\n');
  assert.match(beams[0], /^beam,node_a,node_b,length/);
  assert.equal(beams.length - 1, (vertices * 3) / 2, 'a closed torus: three beams at every node, each shared by two');
  assert.deepEqual(pageErrors, []);
});

test('a paper-figure preset and a surface switch recompute, and land in the URL', async () => {
  await afterRun(() => page.click('button[data-preset^="Fig. 11"]'));
  assert.equal(await page.inputValue('#surface'), 'hyperboloid');
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready');
  assert.match(page.url(), /surface=hyperboloid/);

  // The triangulation's notes are listed under the statistics, the ones a designer should read marked.
  assert.ok(await page.isVisible('#run-notes'));
  assert.ok((await page.locator('#run-notes-list li').count()) >= 1);
  await afterRun(() => page.click('button[data-preset^="Two round bumps"]'));
  assert.match(await page.textContent('#run-notes-summary'), /Notes \(\d+\) · \d+ to read/);
  assert.ok((await page.locator('#run-notes-list li.warn').count()) >= 1);
  await page.click('#run-notes-summary');
  assert.ok(await page.isVisible('#run-notes-list li.warn'));
  assert.match((await page.locator('#run-notes-list li.warn').allTextContents()).join('\n'), /umbilic/);

  await afterRun(() => page.selectOption('#surface', 'sphere'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready');
  assert.match(page.url(), /surface=sphere/);
  assert.ok(await page.isVisible('#param-latitude'));
  assert.deepEqual(pageErrors, []);
});

test('a surface parameter edit re-runs', async () => {
  const before = await page.textContent('#surface-distance');
  const positions = await page.textContent('#face-count');
  await afterRun(() => page.fill('#param-latitude', '40'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready');
  assert.match(page.url(), /s\.latitude=40/);
  assert.ok(before !== (await page.textContent('#surface-distance')) || positions !== (await page.textContent('#face-count')), 'a new mesh');
});

test('views, colour modes and the face tooltip', async () => {
  for (const view of ['initial', 'triangulation', 'hex']) {
    await page.selectOption('#view', view);
    const png = await page.locator('#viewport').screenshot();
    const { count, total } = await nonBackgroundPixels(png);
    assert.ok(count > total * 0.02, `${view}: only ${count} of ${total} pixels drawn`);
  }
  for (const mode of ['convexity', 'regularity', 'area', 'distance', 'planarity']) {
    await page.selectOption('#color', mode);
    assert.ok(await page.isVisible('#legend'), mode);
  }
  await page.uncheck('#flat');
  await page.uncheck('#wireframe');
  await page.click('#fit');
  await page.check('#flat');
  await page.check('#wireframe');
  const box = await page.locator('#viewport canvas').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.move(box.x + box.width / 2 + 3, box.y + box.height / 2 + 2);
  await page.waitForSelector('#tooltip:not([hidden])', { timeout: 5000 });
  const tip = await page.textContent('#tooltip');
  assert.match(tip, /Planarity/);
  // The face's panel label, as on the cut sheet: face f is P(f + 1).
  const [, face, panel] = tip.match(/Face: (\d+) \(\d+ corners\), panel P(\d+)/);
  assert.equal(Number(panel), Number(face) + 1);
  assert.deepEqual(pageErrors, []);
});

test('the structure view draws panels, beams and node axes; its glTF export parses back with the beam count', async () => {
  await page.selectOption('#view', 'structure');
  await page.waitForFunction(() => /\d+ beams/.test(document.getElementById('structure-info').textContent), null, { timeout: RUN_TIMEOUT_MS });
  assert.ok(await page.isVisible('#beamHeight'));
  const info = await page.textContent('#structure-info');
  const beams = Number(info.match(/(\d+) beams/)[1]);
  const png = await page.locator('#viewport').screenshot();
  await page.screenshot({ path: join(artifacts, 'structure.png') });
  const { count, total } = await nonBackgroundPixels(png);
  assert.ok(count > total * 0.02, `structure: only ${count} of ${total} pixels drawn`);
  // The solid model as glTF: three's loader finds the beams, their count and 12 triangles each, panels and axes.
  const glb = await downloadOf('#export-structure-gltf');
  assert.match(glb.name, /-structure\.glb$/);
  const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
  const gltf = await new GLTFLoader().parseAsync(glb.data.buffer.slice(glb.data.byteOffset, glb.data.byteOffset + glb.data.byteLength), '');
  const parts = {};
  gltf.scene.traverse((o) => { if (o.geometry) parts[o.name] = o; });
  assert.equal(parts.beams.userData.beams, beams);
  assert.equal(parts.beams.geometry.index.count, 36 * beams);
  assert.equal(parts.panels.userData.panels, Number(await page.textContent('#face-count')));
  assert.ok(parts.axes.isLineSegments);
  const nodes = (await downloadOf('#export-nodes')).data.toString('utf8').trimEnd().split('\n');
  assert.match(nodes[0], /^node,kind,faces,x,y,z,axis_x/);
  assert.equal(nodes.length - 1, Number(info.match(/(\d+) nodes/)[1]));
  const schedule = (await downloadOf('#export-beams')).data.toString('utf8').trimEnd().split('\n');
  assert.match(schedule[0], /,height_a,height_b,plane_nx,/);
  assert.equal(schedule.length - 1, beams);
  // The offset layer pairs up with the mesh line by line.
  await page.fill('#offset', '0.01');
  const offset = (await downloadOf('#export-offset-obj')).data.toString('utf8');
  const hex = (await downloadOf('#export-obj')).data.toString('utf8');
  assert.equal(offset.split('\n').filter((l) => l.startsWith('f ')).join(), hex.split('\n').filter((l) => l.startsWith('f ')).join());
  assert.equal(offset.split('\n').filter((l) => l.startsWith('v ')).length, hex.split('\n').filter((l) => l.startsWith('v ')).length);
  // A beam height the offset cannot take is named; the next value works.
  await page.fill('#beamHeight', '1000');
  await page.waitForFunction(() => /Structure: beamHeight = 1000/.test(document.getElementById('error').textContent), null, { timeout: RUN_TIMEOUT_MS });
  await page.fill('#beamHeight', '0.01');
  await page.waitForFunction(() => document.getElementById('error').hidden && /\d+ beams/.test(document.getElementById('structure-info').textContent), null, { timeout: RUN_TIMEOUT_MS });
  await page.fill('#beamHeight', '');
  await page.fill('#offset', '');
  await page.selectOption('#view', 'hex');
  assert.deepEqual(pageErrors, []);
});

/** A triangulated patch of a torus as OBJ text. */
function torusPatchObj(n = 24) {
  const lines = [];
  for (let i = 0; i <= n; i++) {
    for (let j = 0; j <= n; j++) {
      const u = (i / n) * Math.PI;
      const v = (j / n) * Math.PI - Math.PI / 2;
      const rho = 1 + 0.4 * Math.cos(v);
      lines.push(`v ${rho * Math.cos(u)} ${rho * Math.sin(u)} ${0.4 * Math.sin(v)}`);
    }
  }
  const id = (i, j) => i * (n + 1) + j + 1;
  for (let i = 0; i < n; i++) {
    for (let j = 0; j < n; j++) lines.push(`f ${id(i, j)} ${id(i + 1, j)} ${id(i + 1, j + 1)}`, `f ${id(i, j)} ${id(i + 1, j + 1)} ${id(i, j + 1)}`);
  }
  return `${lines.join('\n')}\n`;
}

test('an uploaded OBJ mesh is tiled', async (t) => {
  if ((await page.getAttribute('body', 'data-mesh-input')) !== 'true') {
    t.skip('this phex core build has no mesh input (capabilities().meshInput is false)');
    return;
  }
  await afterRun(() => page.setInputFiles('#file', { name: 'torus-patch.obj', mimeType: 'text/plain', buffer: Buffer.from(torusPatchObj()) }));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  assert.match(await page.textContent('#mesh-name'), /torus-patch\.obj/);
  assert.ok(Number(await page.textContent('#face-count')) > 50);
  // The analytic surface's description and parameters are hidden while the upload is what is tiled.
  assert.equal(await page.isVisible('#surface-description'), false);
  assert.equal(await page.isVisible('#surface-params'), false);
  await afterRun(() => page.click('#mesh-clear'));
  assert.equal(await page.isVisible('#surface-description'), true);
  assert.equal(await page.isVisible('#surface-params'), true);
});

test('an upload in site coordinates, far from the origin, is drawn as at the origin', async (t) => {
  if ((await page.getAttribute('body', 'data-mesh-input')) !== 'true') {
    t.skip('this phex core build has no mesh input (capabilities().meshInput is false)');
    return;
  }
  // The same torus patch 5400 km from the origin: in WebGL's 32-bit floats its y would snap to half metres,
  // and its rows collapse onto each other; drawn about its centre it looks as it does at the origin.
  // The surface coloured by its curvature, which comes out alike in both frames (the lays differ in the file's
  // last digits, and the panels' colours with them).
  await page.selectOption('#view', 'curvature');
  const drawn = async (name, obj) => {
    await afterRun(() => page.setInputFiles('#file', { name, mimeType: 'text/plain', buffer: Buffer.from(obj) }));
    assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
    await page.click('#fit');
    return page.locator('#viewport').screenshot();
  };
  const home = await drawn('patch.obj', torusPatchObj());
  const site = torusPatchObj().replace(/^v (\S+) (\S+) (\S+)$/gm, (_, x, y, z) => `v ${Number(x) + 512345.678} ${Number(y) + 5432109.876} ${Number(z) + 250}`);
  const away = await drawn('patch-site.obj', site);
  // The camera frames each alike, and the light shines alike: the two pictures of the model are the same but
  // for a few pixels along edges.
  const { differing, drawn: total } = await page.evaluate(async (pngs) => {
    const decode = async (data) => {
      const bitmap = await createImageBitmap(new Blob([Uint8Array.from(atob(data), (c) => c.charCodeAt(0))]));
      const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
      const ctx = canvas.getContext('2d');
      ctx.drawImage(bitmap, 0, 0);
      return [ctx.getImageData(0, 0, bitmap.width, bitmap.height).data, bitmap.width];
    };
    const [[a, width], [b]] = await Promise.all(pngs.map(decode));
    let differing = 0;
    let drawn = 0;
    for (let i = 0; i < a.length; i += 4) {
      if ((i / 4) % width > 0.6 * width) continue;  // the statistics and notes, which name the coordinates
      const d = Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]);
      if (d > 24) differing++;
      if (a[i] !== a[0] || a[i + 1] !== a[1] || a[i + 2] !== a[2]) drawn++;
    }
    return { differing, drawn };
  }, [home.toString('base64'), away.toString('base64')]);
  assert.ok(differing < 0.02 * total, `${differing} of the ${total} pixels drawn differ between the two`);
  await page.selectOption('#view', 'hex');
  await afterRun(() => page.click('#mesh-clear'));
  assert.deepEqual(pageErrors, []);
});

test('a corrupt or foreign file shows an error banner and the app keeps working', async () => {
  await page.setInputFiles('#file', { name: 'notes.txt', mimeType: 'text/plain', buffer: Buffer.from('hello') });
  await page.waitForSelector('#error:not([hidden])');
  assert.match(await page.textContent('#error'), /notes\.txt/);

  await page.setInputFiles('#file', { name: 'broken.obj', mimeType: 'text/plain', buffer: Buffer.from('v 0 0 0\nv 1 nan 0\nf 1 2 9\n') });
  await page.waitForFunction(() => /broken\.obj/.test(document.getElementById('error').textContent), null, { timeout: RUN_TIMEOUT_MS });
  await page.waitForFunction(() => document.body.dataset.state !== 'running', null, { timeout: RUN_TIMEOUT_MS });
  assert.equal(await page.isVisible('#mesh-source'), false, 'the refused file is dropped');

  await afterRun(() => page.fill('#faces', '400'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready');
  assert.equal(await page.isVisible('#error'), false);
  assert.deepEqual(pageErrors, []);
});

test('a file dropped on the page is opened like a picked one', async () => {
  await page.evaluate(() => {
    const data = new DataTransfer();
    data.items.add(new File(['solid nothing\n'], 'dropped.stl'));
    for (const type of ['dragenter', 'dragover', 'drop']) window.dispatchEvent(new DragEvent(type, { dataTransfer: data, bubbles: true, cancelable: true }));
  });
  await page.waitForFunction(() => /dropped\.stl/.test(document.getElementById('error').textContent), null, { timeout: RUN_TIMEOUT_MS });
  await page.waitForFunction(() => document.body.dataset.state !== 'running', null, { timeout: RUN_TIMEOUT_MS });
  assert.equal(await page.isVisible('#drop-overlay'), false);
  assert.deepEqual(pageErrors, []);
});

test('method global: its options show with their ranges, are named when out of range and land in the URL', async () => {
  await afterRun(() => page.selectOption('#surface', 'ellipsoid'));
  await afterRun(() => page.fill('#faces', '300'));
  assert.equal(await page.isVisible('#anisotropy'), false, 'hidden under the other methods');
  await afterRun(() => page.selectOption('#method', 'global'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  assert.match(await page.textContent('#method-description'), /any surface.*pentagons and heptagons at its singular points/s);
  for (const [id, range] of [['anisotropy', '1 – 8'], ['alignment', '0 – 10'], ['curvatureSizing', '0 – 1']]) {
    assert.ok(await page.isVisible(`#${id}`), id);
    assert.ok((await page.locator(`label:has(#${id})`).textContent()).includes(`(${range})`), id);
  }
  assert.equal(await page.isVisible('#field'), false, "the conjugate methods' field does not apply");
  assert.match(page.url(), /method=global/);
  assert.match(await page.textContent('#triangulation-info'), /^global/);
  assert.match(await page.textContent('#singular-points'), /^\d+/);
  await afterRun(() => page.fill('#anisotropy', '2.5'));
  assert.match(page.url(), /anisotropy=2\.5(&|$)/);
  assert.ok(await page.isVisible('#relay'), 'the second lay can be turned off');
  await afterRun(() => page.selectOption('#relay', 'off'));
  assert.match(page.url(), /relay=off/);
  await afterRun(() => page.selectOption('#relay', 'on'));

  // An option out of range is named; the next value works.
  await afterRun(() => page.fill('#curvatureSizing', '3'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'error');
  assert.match(await page.textContent('#error'), /curvatureSizing/);
  await afterRun(() => page.fill('#curvatureSizing', '0.5'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  assert.match(page.url(), /curvatureSizing=0\.5/);

  // A link restores the method and its options.
  const other = await context.newPage();
  try {
    await other.goto(`${url}/#surface=ellipsoid&faces=300&method=global&alignment=2`);
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    assert.equal(await other.inputValue('#method'), 'global');
    assert.equal(await other.inputValue('#alignment'), '2');
    assert.ok(await other.isVisible('#alignment'));
  } finally {
    await other.close();
  }
  await page.fill('#anisotropy', '2');
  await afterRun(() => page.fill('#curvatureSizing', '0'));
  assert.deepEqual(pageErrors, []);
});

test('method global on a closed upload: the triangulation view marks the singular points, counted in the statistics', async () => {
  // The method stays chosen from the test above; a closed genus-0 blob needs singular points adding up to 12.
  assert.equal(await page.inputValue('#method'), 'global');
  await afterRun(() => page.setInputFiles('#file', { name: 'blob.off', mimeType: 'text/plain', buffer: Buffer.from(blobOFF(2)) }));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  const singular = await page.textContent('#singular-points');
  assert.match(singular, /^\d+ · \+1: \d+.* · sum 12$/, singular);
  await page.selectOption('#view', 'triangulation');
  const png = await page.locator('#viewport').screenshot();
  await page.screenshot({ path: join(artifacts, 'global-field.png') });
  const red = await pixelsOf(png, PENTAGON_RGB);
  assert.ok(red > 50, `${red} pixels of the pentagons' markers`);
  await page.selectOption('#view', 'hex');
  await afterRun(() => page.click('#mesh-clear'));
  await afterRun(() => page.selectOption('#method', 'auto'));
  assert.equal(await page.isVisible('#anisotropy'), false);
  assert.doesNotMatch(page.url(), /anisotropy|curvatureSizing|method=/);
  assert.equal(await page.textContent('#singular-points'), '–');
  assert.deepEqual(pageErrors, []);
});

test('the genus-3 preset loads its bundled model, tiles it with the global method and marks its heptagons', async () => {
  await afterRun(() => page.click('button[data-preset^="Genus 3"]'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  assert.match(await page.textContent('#mesh-name'), /phcpf_3holes_r\.off/);
  assert.equal(await page.inputValue('#method'), 'global');
  assert.match(page.url(), /model=phcpf_3holes_r\.off/);
  // Genus 3: the indices add up to 12 (1 - 3) = -24, so heptagons (-1) there must be.
  const singular = await page.textContent('#singular-points');
  assert.match(singular, /−1: \d+.* · sum -24$/, singular);
  const hex = await page.locator('#viewport').screenshot();
  const { count, total } = await nonBackgroundPixels(hex);
  assert.ok(count > total * 0.05, `only ${count} of ${total} viewport pixels show the mesh`);
  await page.screenshot({ path: join(artifacts, 'global-genus3.png') });
  await page.selectOption('#view', 'triangulation');
  const blue = await pixelsOf(await page.locator('#viewport').screenshot(), HEPTAGON_RGB);
  await page.screenshot({ path: join(artifacts, 'global-genus3-field.png') });
  assert.ok(blue > 50, `${blue} pixels of the heptagons' markers`);
  await page.selectOption('#view', 'hex');

  // Its link opens the model again.
  const other = await context.newPage();
  try {
    await other.goto(page.url());
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    assert.match(await other.textContent('#mesh-name'), /phcpf_3holes_r\.off/);
    assert.equal(await other.textContent('#face-count'), await page.textContent('#face-count'));
  } finally {
    await other.close();
  }
  await afterRun(() => page.click('#mesh-clear'));
  assert.doesNotMatch(page.url(), /model=/);
  await afterRun(() => page.selectOption('#method', 'auto'));
  assert.deepEqual(pageErrors, []);
});

// The near-developable car: the preset comes out planar with no face split (every node of three faces). A share of
// cuts set in the form is sent with the run and kept in the link, and dropped from it at its default.
test('the car preset comes out planar with no face split, and a link keeps a cut share set', async () => {
  await afterRun(() => page.click('button[data-preset^="Near-developable car upload"]'));
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  const planarity = Number((await page.textContent('#planarity-max')).replace(/[^0-9.e+-]/g, ''));
  assert.ok(planarity <= 1e-9, `planarity ${await page.textContent('#planarity-max')}`);
  assert.doesNotMatch(await page.textContent('#iterations'), /split/);
  await afterRun(() => page.click('#mesh-clear'));
  // (The field is among the advanced ones, folded away: set as the form would.)
  const setShare = (value) => afterRun(() => page.$eval('#cutShare', (e, v) => {
    e.value = v;
    e.dispatchEvent(new Event('input', { bubbles: true }));
  }, value));
  await setShare('0.3');
  assert.equal(await page.getAttribute('body', 'data-state'), 'ready', await page.textContent('#error'));
  assert.match(page.url(), /cutShare=0\.3/);
  await setShare('0.1');
  await afterRun(() => page.selectOption('#method', 'auto'));
  assert.doesNotMatch(page.url(), /cutShare/);
  assert.deepEqual(pageErrors, []);
});

test('a link with parameters restores the design', async () => {
  const other = await context.newPage();
  try {
    await other.goto(`${url}/#surface=cyclide&s.uSpan=180&faces=500&duality=tangent&view=initial&color=area`);
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    assert.equal(await other.inputValue('#surface'), 'cyclide');
    assert.equal(await other.inputValue('#param-uSpan'), '180');
    assert.equal(await other.inputValue('#faces'), '500');
    assert.equal(await other.inputValue('#duality'), 'tangent');
    assert.equal(await other.inputValue('#view'), 'initial');
    assert.equal(await other.inputValue('#color'), 'area');
    const faces = Number(await other.textContent('#face-count'));
    assert.ok(faces > 250 && faces < 1000, `face count ${faces}`);

    await other.goto(`${url}/#surface=torus&s.r=5`);
    await other.waitForSelector('body[data-state=error]', { timeout: RUN_TIMEOUT_MS });
    assert.match(await other.textContent('#error'), /\br\b/);
  } finally {
    await other.close();
  }
});

test('the edge statistics count the filler triangles where two boundary panels meet along the curve', async () => {
  // The bumps laid globally at 2000 faces: a side whose boundary runs near an asymptotic direction.
  const other = await context.newPage();
  try {
    await other.goto(`${url}/#surface=freeform&method=global&faces=2000`);
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    const edge = await other.textContent('#edge-info');
    const fillers = Number((edge.match(/(\d+) fillers/) ?? [])[1]);
    assert.ok(fillers >= 8, edge);
    const off = Number((edge.match(/nodes off ([\d.]+) edges max/) ?? [])[1]);
    assert.ok(off < 0.01, edge);
  } finally {
    await other.close();
  }
});

test('the embedding example computes a mesh and follows its sliders', async () => {
  const embed = await context.newPage();
  const errors = [];
  embed.on('pageerror', (e) => errors.push(e.message));
  try {
    await embed.goto(`${url}/embed/`);
    await embed.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    const first = await embed.textContent('#quote');
    assert.match(first, /flat panels/);
    assert.match(first, /[0-9.]+ m² of glass, \d+ m of frame/);
    // The structure's quote: the nodes to connect and the beams, three at each node, as long as the frame.
    const [, nodes, beams, length] = first.match(/(\d+) nodes, (\d+) flat beams \((\d+) m\)/).map(Number);
    assert.ok(nodes > 0 && beams >= nodes, first);
    assert.ok(Math.abs(length - Number(first.match(/(\d+) m of frame/)[1])) <= 1, first);
    const [sheet] = await Promise.all([embed.waitForEvent('download'), embed.click('#sheet')]);
    const svg = readFileSync(await sheet.path(), 'utf8');
    assert.equal((svg.match(/<polygon /g) ?? []).length, Number(first.match(/^(\d+) flat panels/)[1]));
    assert.match(svg, /<svg [^>]*width="[0-9.e+-]+mm"/); // true size: the spans are in metres
    const png = await embed.locator('#view').screenshot();
    const { count, total } = await nonBackgroundPixels(png, page, [0xf7, 0xf9, 0xfb]);
    assert.ok(count > total * 0.03, `only ${count} of ${total} pixels show the canopy`);

    await embed.locator('#panels').fill('800');
    await embed.waitForFunction((q) => document.body.dataset.state === 'ready' && document.getElementById('quote').textContent !== q, first, { timeout: RUN_TIMEOUT_MS });
    await embed.selectOption('#pattern', 'Saddle');
    await embed.waitForFunction(() => document.body.dataset.state === 'running' || /panels/.test(document.getElementById('quote').textContent));
    await embed.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    assert.deepEqual(errors, []);
  } finally {
    await embed.close();
  }
});

test('once loaded, the app works offline (service worker)', async () => {
  const offline = await serve(webDir, 0);
  const other = await context.newPage();
  try {
    await other.goto(offline.url);
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    await other.evaluate(() => navigator.serviceWorker.ready.then(() => undefined));
    offline.server.close();
    offline.server.closeAllConnections();
    await other.reload();
    await other.waitForSelector('body[data-state=ready]', { timeout: RUN_TIMEOUT_MS });
    assert.ok(Number(await other.textContent('#face-count')) > 1000);
  } finally {
    await other.close();
    offline.server.close();
  }
});
