// phex web app — the three.js view: polygon meshes coloured per face, triangulations with field lines,
// the surface coloured by curvature; picking a face under the pointer.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { triangulateFaces } from 'phex';

export const BACKGROUND = 0xeef1f5;
const EDGE_COLOR = 0x1d232b;
const FIELD_COLOR = 0xd4148c;
const PLAIN_COLOR = new THREE.Color(0xb9c6d6);

export class Viewer {
  #renderer;
  #scene = new THREE.Scene();
  #camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
  #controls;
  #group = new THREE.Group();
  #faces = null; // the picked object: {mesh, faceOfTriangle, flatNormals, smoothNormals}
  #edges = null;
  #raycaster = new THREE.Raycaster();
  #framed = false;
  #pending = 0;
  #sun;
  onRender = null;

  constructor(container) {
    this.container = container;
    this.#renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.#renderer.setPixelRatio(window.devicePixelRatio);
    this.#renderer.setClearColor(BACKGROUND);
    container.append(this.#renderer.domElement);
    this.#camera.up.set(0, 0, 1); // the surfaces are modelled with z up
    this.#scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.4);
    sun.position.set(1, 2, 3);
    this.#camera.add(sun); // a light that follows the camera keeps every side readable
    // It shines at the model's centre (fitToView), which for a model in site coordinates is far from the origin.
    this.#sun = sun;
    this.#scene.add(this.#camera, this.#group, sun.target);
    this.#controls = new OrbitControls(this.#camera, this.#renderer.domElement);
    this.#controls.addEventListener('change', () => this.requestRender());
    new ResizeObserver(() => this.resize()).observe(container);
  }

  get canvas() {
    return this.#renderer.domElement;
  }

  resize() {
    const { clientWidth: w, clientHeight: h } = this.container;
    if (w === 0 || h === 0) return;
    this.#renderer.setSize(w, h);
    this.#camera.aspect = w / h;
    this.#camera.updateProjectionMatrix();
    this.render();
  }

  render() {
    cancelAnimationFrame(this.#pending);
    this.#pending = 0;
    this.#renderer.render(this.#scene, this.#camera);
    this.onRender?.();
  }

  /** Renders at the next frame (many changes, one render). */
  requestRender() {
    if (!this.#pending) this.#pending = requestAnimationFrame(() => this.render());
  }

  clear() {
    for (const child of [...this.#group.children]) {
      child.geometry.dispose();  // materials are shared (see surfaceMaterial) and stay
      this.#group.remove(child);
    }
    this.#faces = null;
    this.#edges = null;
  }

  /**
   * Shows a polygon mesh with one colour per face (`faceColor(f, color)` sets it) and its polygon edges.
   * Vertices are duplicated per triangle so faces keep their own colours; the smooth normals come from
   * the shared vertices.
   */
  showPolygons(mesh, faceColor, { flat, wireframe }) {
    const origin = displayOrigin(mesh.positions);
    mesh = { ...mesh, positions: relativeTo(mesh.positions, origin) };
    const { positions, index, faceOfTriangle } = triangulateFaces(mesh);
    const shared = new THREE.BufferGeometry();
    shared.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    shared.setIndex(new THREE.BufferAttribute(index, 1));
    shared.computeVertexNormals();
    const sharedNormals = shared.getAttribute('normal').array;
    shared.dispose();

    // Plain index loops: this runs on the main thread for every result, and views or per-element
    // allocations would make it the longest task of a run.
    const n = faceOfTriangle.length;
    const position = new Float32Array(n * 9);
    const smoothNormals = new Float32Array(n * 9);
    for (let k = 0; k < 3 * n; k++) {
      const v = 3 * index[k];
      const o = 3 * k;
      position[o] = positions[v];
      position[o + 1] = positions[v + 1];
      position[o + 2] = positions[v + 2];
      smoothNormals[o] = sharedNormals[v];
      smoothNormals[o + 1] = sharedNormals[v + 1];
      smoothNormals[o + 2] = sharedNormals[v + 2];
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 9), 3));
    geometry.computeVertexNormals(); // non-indexed: the flat normal of each triangle
    const flatNormals = geometry.getAttribute('normal').array.slice();
    const object = new THREE.Mesh(geometry, surfaceMaterial());
    this.#faces = { mesh: object, faceOfTriangle, flatNormals, smoothNormals };
    this.#edges = edgeLines(mesh.positions, polygonEdges(mesh));
    object.position.copy(origin);
    this.#edges.position.copy(origin);
    this.#group.add(object, this.#edges);
    this.recolor(faceColor);
    this.setShading({ flat, wireframe });
  }

  /** Sets every face's colour again (after a colour-mode change) without rebuilding the geometry. */
  recolor(faceColor) {
    if (!this.#faces) return;
    const { mesh, faceOfTriangle } = this.#faces;
    const attribute = mesh.geometry.getAttribute('color');
    const rgb = attribute.array;
    const color = new THREE.Color();
    let face = -1;
    for (let t = 0; t < faceOfTriangle.length; t++) {
      if (faceOfTriangle[t] !== face) faceColor((face = faceOfTriangle[t]), color);  // a fan's triangles share it
      for (let k = 9 * t; k < 9 * t + 9; k += 3) {
        rgb[k] = color.r;
        rgb[k + 1] = color.g;
        rgb[k + 2] = color.b;
      }
    }
    attribute.needsUpdate = true;
    this.requestRender();
  }

  /** A triangle mesh with per-vertex colours (or plain), its edges and optional polylines. */
  showTriangles({ positions, triangles, fieldLines }, vertexColor, { flat, wireframe }) {
    const origin = displayOrigin(positions);
    positions = relativeTo(positions, origin);
    if (fieldLines) fieldLines = { ...fieldLines, positions: relativeTo(fieldLines.positions, origin) };
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(positions), 3));
    geometry.setIndex(new THREE.BufferAttribute(triangles, 1));
    const colors = new Float32Array(positions.length);
    const color = new THREE.Color();
    for (let v = 0; v < positions.length / 3; v++) {
      if (vertexColor) vertexColor(v, color);
      else color.copy(PLAIN_COLOR);
      colors.set([color.r, color.g, color.b], 3 * v);
    }
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    geometry.computeVertexNormals();
    const object = new THREE.Mesh(geometry, surfaceMaterial(flat));
    object.position.copy(origin);
    this.#group.add(object);
    if (wireframe) {
      const edges = [];
      for (let t = 0; t < triangles.length; t += 3) {
        for (let k = 0; k < 3; k++) edges.push(triangles[t + k], triangles[t + ((k + 1) % 3)]);
      }
      this.#edges = edgeLines(positions, uniqueEdges(edges));
      this.#edges.position.copy(origin);
      this.#group.add(this.#edges);
    }
    if (fieldLines) {
      const lines = polylineObject(fieldLines);
      lines.position.copy(origin);
      this.#group.add(lines);
    }
    this.requestRender();
  }

  setShading({ flat, wireframe }) {
    if (this.#faces) {
      const normal = this.#faces.mesh.geometry.getAttribute('normal');
      normal.array.set(flat ? this.#faces.flatNormals : this.#faces.smoothNormals);
      normal.needsUpdate = true;
    }
    if (this.#edges) this.#edges.visible = wireframe;
    this.requestRender();
  }

  /** Frames what is shown (the bounding sphere of the vertices: tighter than the box's for a flat torus). */
  fitToView() {
    const box = new THREE.Box3().setFromObject(this.#group);
    if (box.isEmpty()) return;
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const first = this.#group.children[0];
    if (first) {
      first.geometry.computeBoundingSphere();
      sphere.copy(first.geometry.boundingSphere).translate(first.position);  // drawn about displayOrigin
    }
    const camera = this.#camera;
    const fov = THREE.MathUtils.degToRad(camera.fov);
    const distance = (sphere.radius / Math.sin(Math.min(fov, fov * camera.aspect) / 2)) * 1.05;
    const direction = this.#framed ? camera.position.clone().sub(this.#controls.target).normalize() : new THREE.Vector3(1, -1.3, 0.9).normalize();
    camera.position.copy(sphere.center).addScaledVector(direction, distance);
    camera.near = distance / 100;
    camera.far = distance * 10;
    camera.updateProjectionMatrix();
    this.#controls.target.copy(sphere.center);
    this.#sun.target.position.copy(sphere.center);
    this.#controls.update();
    this.#framed = true;
    this.requestRender();
  }

  /** The face of the shown polygon mesh under the client point, or -1. */
  pick(clientX, clientY) {
    if (!this.#faces) return -1;
    const rect = this.canvas.getBoundingClientRect();
    const pointer = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1, -((clientY - rect.top) / rect.height) * 2 + 1);
    this.#raycaster.setFromCamera(pointer, this.#camera);
    const [hit] = this.#raycaster.intersectObject(this.#faces.mesh, false);
    return hit ? this.#faces.faceOfTriangle[hit.faceIndex] : -1;
  }

  /**
   * Shows the structure on the panels (phex.structure's `solid`): glass panels with their thickness, the beams
   * and the node axes.
   */
  showStructure(solid) {
    const group = structureGroup(solid);
    for (const child of [...group.children]) this.#group.add(child);
    this.requestRender();
  }

  /** The object to export as glTF. */
  exportable() {
    return this.#group;
  }

  /** A PNG of the current view, as a data URL. */
  snapshot() {
    this.render();
    return this.canvas.toDataURL('image/png');
  }
}

const PANEL_COLOR = 0x9cc7e6;
const BEAM_COLOR = 0x5a6270;
const AXIS_COLOR = 0xc0392b;

/**
 * The structure's solids as three.js objects named panels, beams and axes, each placed at the solid's origin (its
 * positions are relative to it, single precision), with the counts in userData (glTF extras on export: the
 * beams' object carries {beams: count}, beam k being its triangles 12k .. 12k + 11).
 */
export function structureGroup(solid) {
  const group = new THREE.Group();
  const part = (name, { positions, index, count }, material) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    geometry.computeVertexNormals();
    const mesh = new THREE.Mesh(geometry, material);
    mesh.name = name;
    mesh.userData = { [name]: count };
    return mesh;
  };
  const axes = new THREE.BufferGeometry();
  axes.setAttribute('position', new THREE.BufferAttribute(solid.axes.positions, 3));
  const lines = new THREE.LineSegments(axes, lineMaterial(AXIS_COLOR));
  lines.name = 'axes';
  lines.userData = { axes: solid.axes.positions.length / 6 };
  group.add(part('panels', solid.panels, solidMaterial('panels')), part('beams', solid.beams, solidMaterial('beams')), lines);
  for (const child of group.children) child.position.set(...solid.origin);
  return group;
}

function solidMaterial(kind) {
  const key = `solid-${kind}`;
  if (!materials.has(key)) {
    materials.set(key, kind === 'panels'
      ? new THREE.MeshLambertMaterial({ color: PANEL_COLOR, transparent: true, opacity: 0.55, side: THREE.DoubleSide, depthWrite: false })
      : new THREE.MeshLambertMaterial({ color: BEAM_COLOR }));
  }
  return materials.get(key);
}

/**
 * Where to draw a model from: the centre of its box when that lies more than ten times its size from the origin
 * (site coordinates, as the core computes them: PipelineResult::origin), else the origin. WebGL's 32-bit floats
 * keep about 7 digits, half a metre at 5400 km, where a 20 m roof's rows collapsed onto each other; its
 * objects hold their vertices relative to that point and are placed there, and three.js composes the placement
 * with the camera's in double precision.
 */
function displayOrigin(positions) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i += 3) {
    for (let k = 0; k < 3; k++) {
      lo[k] = Math.min(lo[k], positions[i + k]);
      hi[k] = Math.max(hi[k], positions[i + k]);
    }
  }
  const centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
  const size = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  return positions.length > 0 && centre.length() > 10 * size ? centre : new THREE.Vector3();
}

/** The positions less `origin`, in double precision (the same array when the origin is zero). */
function relativeTo(positions, origin) {
  if (origin.lengthSq() === 0) return positions;
  const out = new Float64Array(positions.length);
  for (let i = 0; i < positions.length; i += 3) {
    out[i] = positions[i] - origin.x;
    out[i + 1] = positions[i + 1] - origin.y;
    out[i + 2] = positions[i + 2] - origin.z;
  }
  return out;
}

// One material per look, shared by every result: three.js keeps a shader program only while a material
// uses it, so fresh materials per result would recompile the shaders on the main thread each time.
const materials = new Map();

function surfaceMaterial(flat = false) {
  const key = flat ? 'flat' : 'smooth';
  if (!materials.has(key)) {
    materials.set(key, new THREE.MeshLambertMaterial({
      vertexColors: true,
      side: THREE.DoubleSide,
      flatShading: flat,
      // Push faces back a little so the edges drawn on them are never hidden.
      polygonOffset: true,
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
    }));
  }
  return materials.get(key);
}

function lineMaterial(color) {
  if (!materials.has(color)) materials.set(color, new THREE.LineBasicMaterial({ color }));
  return materials.get(color);
}

/** The polygon boundaries (not the fan triangles) as vertex pairs, each edge once. */
function polygonEdges({ faceOffsets, faceIndices }) {
  const pairs = [];
  for (let f = 0; f + 1 < faceOffsets.length; f++) {
    const first = faceOffsets[f];
    const n = faceOffsets[f + 1] - first;
    for (let i = 0; i < n; i++) pairs.push(faceIndices[first + i], faceIndices[first + ((i + 1) % n)]);
  }
  return uniqueEdges(pairs);
}

function uniqueEdges(pairs) {
  const seen = new Set();
  const out = [];
  for (let i = 0; i < pairs.length; i += 2) {
    const a = Math.min(pairs[i], pairs[i + 1]);
    const b = Math.max(pairs[i], pairs[i + 1]);
    const key = a * 0x100000000 + b;
    if (seen.has(key)) continue;
    seen.add(key);
    out.push(a, b);
  }
  return out;
}

function edgeLines(positions, pairs, color = EDGE_COLOR) {
  const position = new Float32Array(pairs.length * 3);
  for (let i = 0; i < pairs.length; i++) {
    const v = 3 * pairs[i];
    position[3 * i] = positions[v];
    position[3 * i + 1] = positions[v + 1];
    position[3 * i + 2] = positions[v + 2];
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  return new THREE.LineSegments(geometry, lineMaterial(color));
}

function polylineObject({ positions, offsets }) {
  const pairs = [];
  for (let l = 0; l + 1 < offsets.length; l++) for (let p = offsets[l]; p + 1 < offsets[l + 1]; p++) pairs.push(p, p + 1);
  return edgeLines(positions, pairs, FIELD_COLOR);
}
