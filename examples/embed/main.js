// A minimal web configurator built on the phex library, used exactly as a third party would:
// `import ... from 'phex'`, one run per slider change, the previous run aborted.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { createPHex, faceAreas, triangulateFaces } from 'phex';

/** Shapes offered to the customer: an analytic surface of phex and its parameters for a span in metres. */
const PATTERNS = {
  Dome: { surface: 'elliptic-paraboloid', params: (s) => ({ size: s, ra: 0.75 * s, rb: 0.5 * s }) },
  Saddle: { surface: 'hyperbolic-paraboloid', params: (s) => ({ size: s, ra: 0.6 * s, rb: 0.6 * s }) },
  Wave: { surface: 'freeform', params: (s) => ({ size: s, height: 0.2 * s, width: 0.15 * s }) },
  Tower: { surface: 'hyperboloid', params: (s) => ({ a: 0.25 * s, c: 0.35 * s, height: s }) },
};

const $ = (id) => document.getElementById(id);
$('pattern').append(...Object.keys(PATTERNS).map((name) => new Option(name, name)));

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setClearColor(0xf7f9fb);
$('view').append(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.1, 1000);
camera.up.set(0, 0, 1);
scene.add(new THREE.HemisphereLight(0xffffff, 0x99a0aa, 2));
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', () => renderer.render(scene, camera));
const glass = new THREE.MeshLambertMaterial({ color: 0x8fc4e8, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
const frame = new THREE.LineBasicMaterial({ color: 0x2b3138 });
let shown = null;

function resize() {
  const { clientWidth: w, clientHeight: h } = $('view');
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  renderer.render(scene, camera);
}
new ResizeObserver(resize).observe($('view'));

/** Every edge of a polygon mesh once, as pairs of vertex ids [a0, b0, a1, b1, ...]: the panel frames. */
function frameEdges(hex) {
  const seen = new Set();
  const edges = [];
  for (let f = 0; f + 1 < hex.faceOffsets.length; f++) {
    const a = hex.faceOffsets[f];
    const n = hex.faceOffsets[f + 1] - a;
    for (let i = 0; i < n; i++) {
      const u = hex.faceIndices[a + i];
      const v = hex.faceIndices[a + ((i + 1) % n)];
      const key = u < v ? `${u},${v}` : `${v},${u}`;
      if (seen.has(key)) continue;
      seen.add(key);
      edges.push(u, v);
    }
  }
  return edges;
}

function show(hex, edges) {
  if (shown) for (const o of shown) (scene.remove(o), o.geometry.dispose());
  const { positions, index } = triangulateFaces(hex);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  geometry.computeVertexNormals();
  const lines = new THREE.BufferGeometry();
  lines.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  lines.setIndex(edges);
  shown = [new THREE.Mesh(geometry, glass), new THREE.LineSegments(lines, frame)];
  scene.add(...shown);
  geometry.computeBoundingSphere();
  const { center, radius } = geometry.boundingSphere;
  controls.target.copy(center);
  camera.position.copy(center).add(new THREE.Vector3(1, -1.4, 0.9).normalize().multiplyScalar(radius * 2.8));
  controls.update();
  renderer.render(scene, camera);
}

const phex = await createPHex();
let controller = null;
let timer = 0;
let latest = null; // the last mesh shown, for the cut sheet

/** Glass area and frame length (`edges` from frameEdges) of a P-Hex mesh, for the quote. */
function quantities(hex, edges) {
  const area = faceAreas(hex).reduce((a, b) => a + b, 0);
  const p = hex.positions;
  let frame = 0;
  for (let i = 0; i < edges.length; i += 2) {
    const [u, v] = [edges[i], edges[i + 1]];
    frame += Math.hypot(p[3 * u] - p[3 * v], p[3 * u + 1] - p[3 * v + 1], p[3 * u + 2] - p[3 * v + 2]);
  }
  return { area, frame };
}

async function update() {
  const span = Number($('size').value);
  const panels = Number($('panels').value);
  $('size-value').textContent = `${span} m`;
  $('panels-value').textContent = `about ${panels}`;
  controller?.abort();
  const mine = (controller = new AbortController());
  document.body.dataset.state = 'running';
  try {
    const pattern = PATTERNS[$('pattern').value];
    const result = await phex.run({ surface: pattern.surface, surfaceParams: pattern.params(span), faces: panels }, { signal: mine.signal });
    const edges = frameEdges(result.hex);
    show(result.hex, edges);
    latest = result.hex;
    const { faceCount, planarityMax, facesBySize } = result.metrics;
    const { area, frame } = quantities(result.hex, edges);
    // The structure on the panels (beams 20 cm high behind them): its nodes are the connectors to make, three
    // beams at each, and every beam is a flat plate.
    const { report } = await phex.structure(result.hex, { beamHeight: 0.2 });
    $('quote').textContent = `${faceCount} flat panels (${facesBySize['6'] ?? 0} hexagons), ${area.toFixed(1)} m² of glass, ${Math.round(frame)} m of frame; ${report.nodeCount} nodes, ${report.beamCount} flat beams (${Math.round(report.beamLength)} m); flatness ${planarityMax.toExponential(1)}, computed in ${Math.round(result.timings.total)} ms`;
    $('sheet').disabled = false;
    $('error').hidden = true;
    document.body.dataset.state = 'ready';
  } catch (error) {
    if (error.code === 'cancelled') return; // a newer slider position took over
    $('error').textContent = error.message;
    $('error').hidden = false;
    document.body.dataset.state = 'error';
  }
}

// The glass panels laid flat, true to size (the spans are in metres), labelled as the faces: for the cutter.
$('sheet').addEventListener('click', async () => {
  if (!latest) return;
  try {
    const svg = await phex.panels(latest, { unit: 'm' });
    const link = Object.assign(document.createElement('a'), { href: URL.createObjectURL(new Blob([svg], { type: 'image/svg+xml' })), download: 'canopy-panels.svg' });
    link.click();
    setTimeout(() => URL.revokeObjectURL(link.href), 0);
  } catch (error) {
    $('error').textContent = error.message;
    $('error').hidden = false;
  }
});

for (const id of ['pattern', 'size', 'panels']) {
  $(id).addEventListener('input', () => {
    clearTimeout(timer);
    timer = setTimeout(update, 120);
  });
}
update();
