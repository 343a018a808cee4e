// phex web app: computes a P-Hex mesh with the phex library and shows it with three.js.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { createPHex, meshToOBJ, triangulateFaces } from 'phex';

const $ = (id) => document.getElementById(id);
const BACKGROUND = 0xeef1f5;
const EDGE_COLOR = 0x1d232b;
const INVALID_COLOR = new THREE.Color(0xd4148c); // self-intersecting faces, off the planarity scale
const RERUN_DELAY_MS = 350;

// Planarity colour scale (log10), from "far below the goal" to "above the goal", as colour stops.
const SCALE_STOPS = ['#30123b', '#3e6ff2', '#1ccfd5', '#62fc6b', '#d4e735', '#fb8022', '#b21a02'].map((c) => new THREE.Color(c));
const DECADES_BELOW_GOAL = 6;
const DECADES_ABOVE_GOAL = 1;

function setState(state) {
  document.body.dataset.state = state;
}

// ---------------------------------------------------------------- scene

const viewport = $('viewport');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setClearColor(BACKGROUND);
viewport.append(renderer.domElement);

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
camera.up.set(0, 0, 1); // the surfaces are modelled with z up
scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.4);
camera.add(sun); // a light that follows the camera keeps every side readable
sun.position.set(1, 2, 3);
scene.add(camera);

const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', render);

const meshGroup = new THREE.Group();
scene.add(meshGroup);

function render() {
  renderer.render(scene, camera);
}

function resize() {
  const { clientWidth: w, clientHeight: h } = viewport;
  if (w === 0 || h === 0) return;
  renderer.setSize(w, h);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}
new ResizeObserver(resize).observe(viewport);

/** Frames the bounding sphere of the vertices (tighter than that of the bounding box, e.g. for a flat torus). */
function fitToView(geometry) {
  geometry.computeBoundingSphere();
  const sphere = geometry.boundingSphere;
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const distance = (sphere.radius / Math.sin(Math.min(fov, fov * camera.aspect) / 2)) * 1.05;
  const direction = new THREE.Vector3(1, -1.3, 0.9).normalize();
  camera.position.copy(sphere.center).addScaledVector(direction, distance);
  camera.near = distance / 100;
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(sphere.center);
  controls.update();
}

function scaleColor(t, target) {
  const x = THREE.MathUtils.clamp(t, 0, 1) * (SCALE_STOPS.length - 1);
  const i = Math.min(Math.floor(x), SCALE_STOPS.length - 2);
  return target.lerpColors(SCALE_STOPS[i], SCALE_STOPS[i + 1], x - i);
}

/** Maps a planarity value onto [0, 1] of the colour scale around the planarity goal. */
function scalePosition(planarity, tolerance) {
  const low = Math.log10(tolerance) - DECADES_BELOW_GOAL;
  const high = Math.log10(tolerance) + DECADES_ABOVE_GOAL;
  return (Math.log10(Math.max(planarity, 1e-300)) - low) / (high - low);
}

/** Faces as flat-coloured triangles: vertices are duplicated per triangle so each face keeps its own colour. */
function facesObject(mesh, metrics, tolerance) {
  const { positions, index, faceOfTriangle } = triangulateFaces(mesh);
  const triangleCount = faceOfTriangle.length;
  const position = new Float32Array(triangleCount * 9);
  const color = new Float32Array(triangleCount * 9);
  const c = new THREE.Color();
  for (let t = 0; t < triangleCount; t++) {
    const f = faceOfTriangle[t];
    if (metrics.selfIntersecting[f]) c.copy(INVALID_COLOR);
    else scaleColor(scalePosition(metrics.planarity[f], tolerance), c);
    for (let k = 0; k < 3; k++) {
      const v = index[3 * t + k];
      position.set(positions.subarray(3 * v, 3 * v + 3), 9 * t + 3 * k);
      color.set([c.r, c.g, c.b], 9 * t + 3 * k);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(color, 3));
  geometry.computeVertexNormals();
  const material = new THREE.MeshLambertMaterial({
    vertexColors: true,
    side: THREE.DoubleSide,
    // Push faces back a little so the polygon edges drawn on them are never hidden.
    polygonOffset: true,
    polygonOffsetFactor: 1,
    polygonOffsetUnits: 1,
  });
  return new THREE.Mesh(geometry, material);
}

/** The polygon boundaries (not the fan triangles), each edge once. */
function edgesObject(mesh) {
  const { positions, faceOffsets, faceIndices } = mesh;
  const seen = new Set();
  const segments = [];
  for (let f = 0; f + 1 < faceOffsets.length; f++) {
    const first = faceOffsets[f];
    const n = faceOffsets[f + 1] - first;
    for (let i = 0; i < n; i++) {
      const a = faceIndices[first + i];
      const b = faceIndices[first + ((i + 1) % n)];
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      if (seen.has(key)) continue;
      seen.add(key);
      segments.push(a, b);
    }
  }
  const position = new Float32Array(segments.length * 3);
  segments.forEach((v, i) => position.set(positions.subarray(3 * v, 3 * v + 3), 3 * i));
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  return new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: EDGE_COLOR }));
}

function showMesh(result, tolerance) {
  for (const child of [...meshGroup.children]) {
    child.geometry.dispose();
    child.material.dispose();
    meshGroup.remove(child);
  }
  const faces = facesObject(result.hex, result.metrics, tolerance);
  meshGroup.add(faces, edgesObject(result.hex));
  fitToView(faces.geometry);
  render();
}

// ---------------------------------------------------------------- panels

const fmt = (x) => (x === 0 ? '0' : x.toExponential(2));
const ms = (x) => Math.round(x).toString();

function showStats(result) {
  const { metrics, solve, timings } = result;
  $('face-count').textContent = String(metrics.faceCount);
  $('faces-by-size').textContent = Object.entries(metrics.facesBySize)
    .map(([size, count]) => `${size}-gons ${count}`)
    .join(', ');
  $('planarity-max').textContent = fmt(metrics.planarityMax);
  $('planarity-mean').textContent = fmt(metrics.planarityMean);
  $('invalid-faces').textContent = String(metrics.selfIntersectingCount);
  $('iterations').textContent = `${solve.iterations}${solve.converged ? '' : ' (not converged)'}`;
  $('timings').textContent = ['triangulate', 'dualize', 'planarize', 'measure']
    .map((stage) => `${stage} ${ms(timings[stage] ?? 0)}`)
    .concat(`total ${ms(timings.total)}`)
    .join(' · ');
}

function showLegend(tolerance) {
  const stops = SCALE_STOPS.map((c, i) => `#${c.getHexString()} ${((100 * i) / (SCALE_STOPS.length - 1)).toFixed(1)}%`);
  $('legend-bar').style.background = `linear-gradient(to right, ${stops.join(', ')})`;
  $('legend-low').textContent = `≤ ${fmt(tolerance * 10 ** -DECADES_BELOW_GOAL)}`;
  $('legend-high').textContent = `≥ ${fmt(tolerance * 10 ** DECADES_ABOVE_GOAL)}`;
  $('legend-goal-value').textContent = fmt(tolerance);
  $('legend-goal').style.left = `${100 * scalePosition(tolerance, tolerance)}%`;
}

function showError(message) {
  $('error').textContent = message;
  $('error').hidden = false;
}

function clearError() {
  $('error').hidden = true;
  $('error').textContent = '';
}

function showProgress({ stage, fraction, message }) {
  $('progress').value = fraction;
  $('stage').textContent = `${stage}: ${message}`;
}

// ---------------------------------------------------------------- parameters and runs

let phex;
let surfaces = [];
let lastResult = null;
let lastParams = null;
let running = null; // AbortController of the run in flight
let rerunTimer = 0;

/** Reads a number input; an empty or unparsable field is passed on as NaN, for the library to name it. */
function numberOf(input) {
  return input.value.trim() === '' ? Number.NaN : Number(input.value);
}

function buildSurfaceParams(spec) {
  const fieldset = $('surface-params');
  fieldset.replaceChildren();
  for (const p of spec.parameters) {
    const label = document.createElement('label');
    label.textContent = p.name;
    const input = document.createElement('input');
    Object.assign(input, { type: 'number', step: 'any', value: String(p.default), min: String(p.min), max: String(p.max) });
    input.id = `param-${p.name}`;
    input.dataset.param = p.name;
    const hint = document.createElement('small');
    hint.textContent = p.description;
    label.append(input, hint);
    fieldset.append(label);
  }
  $('surface-description').textContent = spec.description;
}

function readParams() {
  const surfaceParams = {};
  for (const input of $('surface-params').querySelectorAll('input')) surfaceParams[input.dataset.param] = numberOf(input);
  return {
    surface: $('surface').value,
    surfaceParams,
    faces: numberOf($('faces')),
    tolerance: numberOf($('tolerance')),
    duality: $('duality').value,
  };
}

async function compute() {
  clearTimeout(rerunTimer);
  running?.abort();
  const controller = new AbortController();
  running = controller;
  const params = readParams();
  setState('running');
  $('cancel').disabled = false;
  showProgress({ stage: 'start', fraction: 0, message: 'starting' });
  try {
    const result = await phex.run(params, { onProgress: showProgress, signal: controller.signal });
    if (running !== controller) return;
    lastResult = result;
    lastParams = params;
    clearError();
    showMesh(result, params.tolerance);
    showStats(result);
    showLegend(params.tolerance);
    $('export-obj').disabled = false;
    $('stage').textContent = `done in ${ms(result.timings.total)} ms`;
    setState('ready');
  } catch (error) {
    if (running !== controller) return; // superseded by a newer run
    if (error.code === 'cancelled') {
      $('stage').textContent = 'cancelled';
      setState(lastResult ? 'ready' : 'error');
    } else {
      showError(error.message);
      $('stage').textContent = '';
      setState('error');
    }
  } finally {
    if (running === controller) {
      running = null;
      $('cancel').disabled = true;
      $('progress').value = 0;
    }
  }
}

function scheduleRun() {
  clearTimeout(rerunTimer);
  rerunTimer = setTimeout(compute, RERUN_DELAY_MS);
}

function exportObj() {
  if (!lastResult) return;
  const blob = new Blob([meshToOBJ(lastResult.hex)], { type: 'text/plain' });
  const link = document.createElement('a');
  link.href = URL.createObjectURL(blob);
  link.download = `phex-${lastParams.surface}-${lastResult.metrics.faceCount}.obj`;
  link.click();
  URL.revokeObjectURL(link.href);
}

async function start() {
  setState('running');
  try {
    phex = await createPHex();
    surfaces = await phex.surfaces();
  } catch (error) {
    showError(`phex could not start: ${error.message}`);
    setState('error');
    return;
  }
  $('surface').replaceChildren(...surfaces.map((s) => new Option(s.name, s.name, s.name === 'torus', s.name === 'torus')));
  buildSurfaceParams(surfaces.find((s) => s.name === $('surface').value));

  $('surface').addEventListener('change', () => {
    buildSurfaceParams(surfaces.find((s) => s.name === $('surface').value));
    scheduleRun();
  });
  $('params').addEventListener('input', (event) => {
    if (event.target !== $('surface')) scheduleRun();
  });
  $('params').addEventListener('submit', (event) => {
    event.preventDefault();
    compute();
  });
  $('cancel').addEventListener('click', () => running?.abort());
  $('export-obj').addEventListener('click', exportObj);
  window.addEventListener('error', (event) => showError(String(event.message)));
  window.addEventListener('unhandledrejection', (event) => showError(String(event.reason?.message ?? event.reason)));

  resize();
  await compute();
}

start();
